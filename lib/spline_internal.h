/*
 * spline_internal.h — helpers shared by lib/spline*.c, lib/cover*.c and lib/check_coverage.c (not public).
 */
#ifndef AMP_SPLINE_INTERNAL_H
#define AMP_SPLINE_INTERNAL_H

#include "ampath/spline.h"

/** Parameter @p t of direction @p d clamped to the domain. */
double amp_spl_clamp(const amp_spline *s, int d, double t);
/** Knot span of t (NURBS Book A2.1, right-continuous, no snapping); @p hint is tried first. */
size_t amp_spl_span(const double *U, int k, size_t n, double t, size_t hint);
/** The k non-zero basis functions on span i at t (NURBS Book A2.2). */
void amp_spl_basis(const double *U, size_t i, int k, double t, double *N);
/** Basis functions and derivatives up to nd: ders[q*k + j] (NURBS Book A2.3). */
void amp_spl_basis_ders(const double *U, size_t i, int k, double t, int nd, double *ders);
/** |det J| of trivariate @p v at parameters @p p (0 where evaluation fails). */
double amp_spl_det_jacobian(const amp_spline *v, const double *p);
/** Volume of trivariate @p v (Gauss-Legendre, 3 points per direction per cell of a 12^3 grid); *jmax (may
 *  be NULL) receives the largest |det J| at the quadrature points. */
double amp_spl_volume(const amp_spline *v, double *jmax);

#endif
