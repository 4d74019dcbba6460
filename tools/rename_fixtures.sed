# tools/rename_fixtures.sed — test helpers and fixtures under one prefix, fx_, outside the library's amp_
# namespace, and one test-registration style (Check's tcase_add_test); the torus written once (fx_torus).
# For test files from other branches: sed -i -E -f tools/rename_fixtures.sed tests/test_*.c
# (then drop the merge shims at the end of tests/testutil.h, tests/meshfix.h and tests/fixture_geom.h).
s/\bamp_fix_torus\(([^,]+),/fx_torus(\1, amp_v3(0, 0, 0),/g
s/\bamp_fix_(box|rand|torus_sdf|mesh_dist|helix_point|helix_axis_dist|components)\b/fx_\1/g
s/\bamp_fixture_(helix|rings)\b/fx_\1/g
s/\bamp_test_run_tool(_ex)?\b/fx_run_tool\1/g
s/\bamp_test_(tmp|prog|msleep|split|failalloc_init|failalloc)\b/fx_\1/g
s/\bAMP_TEST_MAXARGS\b/FX_MAXARGS/g
s/\bAMP_TEST_MAIN\b/FX_TEST_MAIN/g
s/\bAMP_ADD_TEST\(/tcase_add_test(/g
