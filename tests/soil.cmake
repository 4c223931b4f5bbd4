# Soil phase the Drucker-Prager SPH soil of sph_node/soil/sph_soil.[ch] against
# closed forms (return mapping, elastic and Jaumann stress rates, equilibrium of a uniform
# stress), and its cases end to end through `lahar check` at CI resolution (the cases' own bounds;
# measured values in docs/bench/validation.md, "Soil").
lahar_test(soil_sph_unit PROGRAM test_sph_soil SOURCES test_sph_soil.c
  LIBS lahar_sph LABELS fast soil TIMEOUT 120)

# Geostatic layer: sigma_v = rho g z and sigma_h = K0 sigma_v within 5 %, no creep (4 s wall).
lahar_test(soil_geostatic_2d COMMAND sh ${LAHAR_TEST_DIR}/validation_check.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/soil_geostatic_2d.yaml ${CMAKE_CURRENT_BINARY_DIR}/soil/geostatic_2d
  LABELS validation slow soil TIMEOUT 600 ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")

# The soil's ghost-layer wall stress (sph.soil_wall_stress: ghost, sph_coupling_set_soil_wall):
# the row resting on the floor within 5 % of rho g z (the penalty wall alone: +23 % in 2D, +18 %
# in 3D), every row deeper than H/4 within 7 % in 2D (the row-by-row mode of the start-up, +-3.4 %
# about the mean in 2D, +-13 % in 3D, docs/bench/validation.md), the 2-row bins, K0 and the creep as in
# soil_geostatic_2d.
lahar_test(soil_geostatic_ghost_2d COMMAND sh ${LAHAR_TEST_DIR}/validation_check.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/soil_geostatic_ghost_2d.yaml
          ${CMAKE_CURRENT_BINARY_DIR}/soil/geostatic_ghost_2d
  LABELS validation slow soil TIMEOUT 600 ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")
lahar_test(soil_geostatic_ghost_3d COMMAND sh ${LAHAR_TEST_DIR}/validation_check.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/soil_geostatic_ghost_3d.yaml
          ${CMAKE_CURRENT_BINARY_DIR}/soil/geostatic_ghost_3d
  LABELS validation slow soil TIMEOUT 600 ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")

# Soil-DEM friction (Trujillo-Vela et al. 2020 eq. 22-27): a soil block on a 30 deg plane with mu_phi = 0.3 slides
# at g (sin - mu_phi cos) within 5 %; on a 15 deg plane with mu_phi = 0.5 it stays put (|a| within
# 5 % of g sin theta), and moves less than 1 mm in 0.4 s.
lahar_test(soil_block_incline_2d COMMAND sh ${LAHAR_TEST_DIR}/validation_check.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/soil_block_incline_2d.yaml
          ${CMAKE_CURRENT_BINARY_DIR}/soil/block_incline_2d
  LABELS validation slow soil TIMEOUT 600 ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")
lahar_test(soil_block_incline_stick_2d COMMAND sh ${LAHAR_TEST_DIR}/validation_check.sh $<TARGET_FILE:lahar>
          ${CMAKE_SOURCE_DIR}/cases/soil_block_incline_stick_2d.yaml ${CMAKE_CURRENT_BINARY_DIR}/soil/block_incline_stick_2d
          displacement_m<=0.001 displacement_m>=-0.001
  LABELS validation slow soil TIMEOUT 600 ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")

# Granular collapse (Bui 2008 aluminium bars, reference 04a) at dx = 10 mm: no particle through the
# floor or the wall, settled, deposit at or below the angle of repose; the run-out is reported.
lahar_test(soil_granular_collapse_2d COMMAND sh ${LAHAR_TEST_DIR}/validation_check.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/granular_collapse_2d.yaml ${CMAKE_CURRENT_BINARY_DIR}/soil/granular_collapse_2d dx=0.01 runout_m>=0.25
  LABELS validation slow soil TIMEOUT 600 ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")

# Darcy (Trujillo-Vela et al. 2020 eq. 8-10): water driven through a soil at i = 0.5 flows at k_h i within 5 %.
lahar_test(soil_darcy_column_2d COMMAND sh ${LAHAR_TEST_DIR}/validation_check.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/darcy_column_2d.yaml ${CMAKE_CURRENT_BINARY_DIR}/soil/darcy_column_2d
  LABELS validation slow soil TIMEOUT 600 ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")

# Dry-sand column collapses (phi = 30 deg) against the run-out scalings of Lube et al. (2005) and
# Lajeunesse et al. (2005) (docs/soil/column_collapse_scalings.md): the mass run-out L_99 inside
# the band of the two experiments at a = 1 and a = 2, the deposit at rest (E_k end / peak < 0.01),
# no particle through the floor or wall, the surface at or below phi. dx = 10 mm (the cases' 5 mm
# and the 2.5 mm sweep in docs/bench/validation.md); about 5 s and 10 s on 1 thread.
lahar_test(soil_granular_column_a1_2d COMMAND sh ${LAHAR_TEST_DIR}/validation_check.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/granular_column_a1_2d.yaml
          ${CMAKE_CURRENT_BINARY_DIR}/soil/granular_column_a1_2d dx=0.01
  LABELS validation slow soil TIMEOUT 600 ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")
lahar_test(soil_granular_column_a2_2d COMMAND sh ${LAHAR_TEST_DIR}/validation_check.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/granular_column_a2_2d.yaml
          ${CMAKE_CURRENT_BINARY_DIR}/soil/granular_column_a2_2d dx=0.01
  LABELS validation slow soil TIMEOUT 600 ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")
# The a = 1 column with the soil's ghost wall stress (sph.soil_wall_stress: ghost), at the case's
# dx 5 mm: comes to rest (E_k end / peak < 0.01) with L_99 inside the band, no particle through the
# floor or wall. Without the ghosts' share of the velocity gradient (sph_coupling.h) it blows up
# within 0.1 s (particles thrown out, E_k growing). About 10 s of CPU on 1 thread.
lahar_test(soil_granular_column_a1_ghost_2d COMMAND sh ${LAHAR_TEST_DIR}/validation_check.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/granular_column_a1_ghost_2d.yaml ${CMAKE_CURRENT_BINARY_DIR}/soil/granular_column_a1_ghost_2d
  LABELS validation slow soil TIMEOUT 600 ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")
