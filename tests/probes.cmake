# Pressure probes (case section probes:, sph_node/sph_probes.h, OUT/gauges.h5): a tank at rest
# (cases/hydrostatic_2d.yaml at dx = 10 mm, 0.5 s) with probes on the walls (a point and a 9 mm
# sensor, Adami et al. 2012 eq. 27), on the floor, in the water (Shepard), above it (dry: 0) and
# one at 100 Hz: every wetted probe's mean over 0.3-0.5 s within 1 % of rho g h of rho g (h - y),
# the 100 Hz probe one sample per 10 ms slot, a case without probes writes no gauges.h5.
# The bad-probe fixtures are in tests/bad_cases/probe_*.yaml (case_bad_inputs).
if(NOT DEFINED LAHAR_OUTPUT_PYTHON)
  set(LAHAR_OUTPUT_PYTHON python3)
endif()
add_test(NAME probes_tank_2d
  COMMAND ${LAHAR_OUTPUT_PYTHON} ${LAHAR_TEST_DIR}/probes_check.py $<TARGET_FILE:lahar>
          ${CMAKE_CURRENT_BINARY_DIR}/probes/tank_2d)
set_tests_properties(probes_tank_2d PROPERTIES LABELS "sph;probes" TIMEOUT 300)
