# Granular flow impact on a wall (Trujillo-Vela et al. 2020 section 5.3): `lahar check` on
# cases/granular_impact_3d.yaml at CI resolution, dx = 50 mm (360 particles; the paper's 12.5 mm is
# 64 times the particles) over the full 1.8 m chute, in-process on 2 threads (~11 s each at load 3).
# The case's metrics (reference granular_impact, coordinator/check/check_soil_impact.c): no soil particle through the
# wall, the bed or a side wall (followed by id; over the wall's top is overtopping, allowed); the
# particle count; the impulse of every body's force against M g_t T - dP within 5 % (action and
# reaction of the coupling); the 10 ms peak force within a factor 2 of rho u^2 A of the arriving
# soil + M g sin(theta); the first impact between the frictionless dam-break front on the slope
# and a rigid block sliding with mu_phi = tan 26 deg. Measured values: docs/bench/validation.md ("Granular
# impact on a wall").
lahar_test(soil_granular_impact_3d
  COMMAND sh ${LAHAR_TEST_DIR}/validation_check.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/granular_impact_3d.yaml
          ${CMAKE_CURRENT_BINARY_DIR}/soil/granular_impact_3d dx=0.05 end=1.2 threads=2
  LABELS slow validation soil TIMEOUT 600 ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")
# The same with no soil-bed friction (mu_phi = 0 on every DEM surface): the sand arrives unbraked and
# the check must fail on its peak (measured 3243 N against an estimate of 631 N at dx 50 mm, 45 deg;
# the case itself: 439 N against 487 N). Shows that the peak metric catches broken friction.
lahar_test(soil_granular_impact_no_friction_fails_3d
  COMMAND sh ${LAHAR_TEST_DIR}/impact_check.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/granular_impact_3d.yaml
          ${CMAKE_CURRENT_BINARY_DIR}/soil/granular_impact_no_friction_3d materials.sand.friction=0
          -- dx=0.05 end=1.2 threads=2
  LABELS slow validation soil TIMEOUT 600
  ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}" EXPECT_FAIL=peak_to_load_estimate_log LAHAR_CHECK_NO_PLOT=1)
