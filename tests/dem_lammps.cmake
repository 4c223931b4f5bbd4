# The LAMMPS DEM engine (dem_node/engines/lammps): analytic checks of the engine, and a coupled run
# with `lahar run` against the spheropoly engine. Without liblammps the tests exist and report
# SKIP (exit 77), so a build without the engine says what it did not test.
add_executable(test_dem_lammps ${LAHAR_TEST_DIR}/test_dem_lammps.c ${LAHAR_TEST_DIR}/dem_test_util.c)
target_include_directories(test_dem_lammps PRIVATE ${LAHAR_TEST_DIR})
target_link_libraries(test_dem_lammps PRIVATE lahar_dem)
add_test(NAME test_dem_lammps COMMAND test_dem_lammps)
set_tests_properties(test_dem_lammps PROPERTIES LABELS "fast;dem;lammps" TIMEOUT 300 SKIP_RETURN_CODE 77)

# A coupled run through `lahar run` (processes, private network namespace): a disc sinking in water
# onto the floor, lammps vs spheropoly (dem_lammps_coupled.sh says why the tolerance). ~20 s.
add_test(NAME dem_lammps_coupled
         COMMAND sh ${LAHAR_TEST_DIR}/dem_lammps_coupled.sh $<TARGET_FILE:lahar> ${CMAKE_CURRENT_BINARY_DIR}/dem_lammps_coupled
                 ${LAHAR_TEST_PYTHON})
set_tests_properties(dem_lammps_coupled PROPERTIES LABELS "slow;netns;lammps;coupling" TIMEOUT 600)
if(NOT LAHAR_HAVE_LAMMPS)
  set_tests_properties(dem_lammps_coupled PROPERTIES DISABLED TRUE)
endif()
