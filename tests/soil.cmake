# Soil phase (issue 5, brief SOIL): the Drucker-Prager SPH soil of sph_node/sph_soil.[ch] against
# closed forms (return mapping, elastic and Jaumann stress rates, equilibrium of a uniform
# stress), and its cases end to end through `lahar check` at CI resolution (the cases' own bounds;
# measured values in cases/README.md, "Soil").
add_executable(test_sph_soil ${LAHAR_TEST_DIR}/test_sph_soil.c)
target_link_libraries(test_sph_soil PRIVATE lahar_sph)
add_test(NAME soil_sph_unit COMMAND test_sph_soil)
set_tests_properties(soil_sph_unit PROPERTIES LABELS "fast;soil" TIMEOUT 120)

if(NOT DEFINED LAHAR_OUTPUT_PYTHON)
  set(LAHAR_OUTPUT_PYTHON python3)
endif()
# Geostatic layer: sigma_v = rho g z and sigma_h = K0 sigma_v within 5 %, no creep (4 s wall).
add_test(NAME soil_geostatic_2d
  COMMAND sh ${LAHAR_TEST_DIR}/validation_check.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/soil_geostatic_2d.yaml
          ${CMAKE_CURRENT_BINARY_DIR}/soil/geostatic_2d)
set_tests_properties(soil_geostatic_2d PROPERTIES LABELS "validation;slow;soil" TIMEOUT 600
  ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")
