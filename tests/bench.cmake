# `lahar bench` (tools/bench.py): the --quick preset on two validation cases plus the
# overhead (processes over LCM in a private namespace: label netns) and subcycling scenes, then
# tests/test_bench_output.py checks the CSVs, PNGs and summary.md it wrote: columns, particles x
# steps / wall, the error column against each run's check.json, n ~ dx^-D, one DEM substep per
# step when dt_max is forced to the DEM's stable dt. Speed is never asserted.
set(LAHAR_BENCH_OUT ${CMAKE_CURRENT_BINARY_DIR}/bench_quick)
set(LAHAR_BENCH_QUICK_CASES poiseuille_2d,dam_break_2d,soil_block_incline_2d)
lahar_test(bench_quick COMMAND sh -c "rm -rf \"$1\" && \"$0\" bench --quick --cases $3 -o \"$1\" && \"$2\" \"$4\" \"$1\" pareto,overhead,subcycle $3" $<TARGET_FILE:lahar> ${LAHAR_BENCH_OUT} ${LAHAR_BENCH_PYTHON} ${LAHAR_BENCH_QUICK_CASES} ${LAHAR_TEST_DIR}/test_bench_output.py
  LABELS slow netns bench TIMEOUT 600 ENVIRONMENT "LAHAR_PYTHON=${LAHAR_BENCH_PYTHON}")

# The converged solution the bench measures an experiment case's error against (Richardson
# extrapolation, or the finest run when the sweep does not converge monotonically), on synthetic
# sweeps with a known limit and order.
lahar_test(bench_converged_reference COMMAND ${LAHAR_BENCH_PYTHON} ${LAHAR_TEST_DIR}/test_bench_converged.py
  LABELS fast bench TIMEOUT 60)
