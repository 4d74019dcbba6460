# tools/cite.sed — one form of citation ([P1 §x], [P2 §x], docs/interfaces.md §N), for comments in any source file:
#   sed -i -f tools/cite.sed FILE...
# "SPEC §N" (an outside page) becomes the in-repository interface reference docs/interfaces.md §N
# (same section numbers; the spline file, helix, layers and fields are §4.1-§4.4 there); the papers are
# cited as [P1 §x] (volumetric, "paper §x" and "paper 1 §x" alike) and [P2 §x] (continuous planar
# paths), defined in docs/ARCHITECTURE.md. "issue N" citations need a sentence of their own: list them
# with  grep -rnE 'issue [0-9]+' lib include tools tests bridge  and say what the issue asked instead.
s/SPEC §\([0-9][0-9.]*[0-9]\)/docs\/interfaces.md §\1/g
s/SPEC §\([0-9]\)/docs\/interfaces.md §\1/g
s/paper 1 §\([0-9][0-9.]*[0-9]\)/[P1 §\1]/g
s/paper 1 §\([0-9]\)/[P1 §\1]/g
s/paper 2 §\([0-9][0-9.]*[0-9]\)/[P2 §\1]/g
s/paper 2 §\([0-9]\)/[P2 §\1]/g
s/paper §\([0-9][0-9.]*[0-9]\)/[P1 §\1]/g
s/paper §\([0-9]\)/[P1 §\1]/g
