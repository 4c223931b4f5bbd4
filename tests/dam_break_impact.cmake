# Wall impact pressure of a dam break against experiments. Lobovsky et al. 2014,
# H = 300 mm (cases/dam_break_lobovsky_2d.yaml at dx = 10 mm, 1 s, one thread; 9 s of CPU, 20-45 s
# on the loaded 2-core machine): impact time at sensor 1 within 5 %, the 10 ms mean peak pressure of
# sensors 1-2 within [0.5, 2] x the experiment's, water levels H1-H4 (the case's level gauges)
# within 0.05 H (mean over t* <= 5.5). Data: docs/references-data/lobovsky_2014_*.csv; comparison: tools/compare_lobovsky.py;
# measured values: cases/README.md "Lobovsky dam break".
lahar_test(sph_dam_break_lobovsky_2d COMMAND ${LAHAR_OUTPUT_PYTHON} ${LAHAR_TEST_DIR}/lobovsky_check.py $<TARGET_FILE:lahar> ${CMAKE_CURRENT_BINARY_DIR}/impact/lobovsky_2d
  LABELS sph validation slow TIMEOUT 300)
# The same with the Riemann-solver scheme (sph.scheme: riemann, Zhang, Hu & Adams 2017; sph_node/fluid/sph_riemann.h):
# the same bounds. Measured (dx 10 mm): impact t* within 0.2 %, sensor 1 peak 10.2 against delta-SPH's 12.9
# rho g H (the experiment's 3.04): docs/bench/impact_pressure.md.
lahar_test(sph_dam_break_lobovsky_2d_riemann COMMAND ${LAHAR_OUTPUT_PYTHON} ${LAHAR_TEST_DIR}/lobovsky_check.py $<TARGET_FILE:lahar>
  ${CMAKE_CURRENT_BINARY_DIR}/impact/lobovsky_2d_riemann sph.scheme=riemann sph.alpha=~ sph.delta=~
  LABELS sph validation slow TIMEOUT 300)
