# tools/rename_checkers.sed — the checker renames of the house refactoring (one checker module, include/ampath/check.h),
# for files written on other branches: sed -i -f tools/rename_checkers.sed FILE...
# amp_cover_measure_gap/amp_coverage_gap became amp_check_coverage with another signature
# (see include/ampath/check.h): convert those calls by hand.
s/\bamp_gouge_check\b/amp_check_gouge/g
s/\bamp_stroke_check_radii\b/amp_check_stroke_radii/g
s/\bamp_pathset_stroke_check\b/amp_check_path_stroke/g
s/\bamp_stroke_check\b/amp_check_stroke/g
s/\bamp_hold_check\b/amp_check_hold/g
s/"ampath\/gouge\.h"/"ampath\/check.h"/g
s/"ampath\/support_check\.h"/"ampath\/check.h"/g
s/<ampath\/gouge\.h>/<ampath\/check.h>/g
s/<ampath\/support_check\.h>/<ampath\/check.h>/g
