# Pressure probes (case section probes:, sph_node/probes/sph_probes.h, OUT/gauges.h5): a tank at rest
# (cases/hydrostatic_2d.yaml at dx = 10 mm, 0.5 s) with probes on the walls (a point and a 9 mm
# sensor, Adami et al. 2012 eq. 27), on the floor, in the water (Shepard), above it (dry: 0) and
# one at 100 Hz: every wetted probe's mean over 0.3-0.5 s within 1 % of rho g h of rho g (h - y),
# the 100 Hz probe one sample per 10 ms slot, a case without probes writes no gauges.h5; a level
# gauge (kind: level) in the middle reads h within 0.05 dx at every sample (measured 0.0016 dx).
# The bad-probe fixtures are in tests/bad_cases/probe_*.yaml (case_bad_inputs).
lahar_test(probes_tank_2d COMMAND ${LAHAR_OUTPUT_PYTHON} ${LAHAR_TEST_DIR}/probes_check.py $<TARGET_FILE:lahar>
          ${CMAKE_CURRENT_BINARY_DIR}/probes/tank_2d
  LABELS sph probes TIMEOUT 300)
# 3D: cases/hydrostatic_3d.yaml at dx 10 mm, 0.1 s, disc sensors (20 mm on a wall, 10 mm on the
# floor) and a point in the water within 1 % of rho g h (measured -0.27, -0.24, -0.08 %); a level
# gauge at the centre within 0.05 dx of h (measured 0.0088 dx).
lahar_test(probes_tank_3d COMMAND ${LAHAR_OUTPUT_PYTHON} ${LAHAR_TEST_DIR}/probes_check.py $<TARGET_FILE:lahar>
          ${CMAKE_CURRENT_BINARY_DIR}/probes/tank_3d --3d
  LABELS sph probes TIMEOUT 300)

# Wall-force chatter (sph.penalty_stiffness): a tank at rest with penalty walls at a step 8 times
# below the CFL step; the step-to-step change of the wall force is <= 0.5 % of rho g h^2 / 2 with
# the acoustic stiffness and >= 2 % with Trujillo-Vela et al. 2020 eq. 15's K_n = 0.1 m / dt^2 (measured 0.20 %
# and 9.05 %; docs/bench/wall_force_chatter.md). ~40 s on 1 thread.
lahar_test(sph_wall_force_chatter_2d COMMAND ${LAHAR_OUTPUT_PYTHON} ${LAHAR_TEST_DIR}/force_chatter_check.py $<TARGET_FILE:lahar> ${CMAKE_CURRENT_BINARY_DIR}/probes/force_chatter_2d
  LABELS sph probes slow TIMEOUT 300)
