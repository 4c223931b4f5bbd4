# sph.initial_pressure (brief M): hydrostatic block densities against the inverse EOS (linear, Tait).
add_executable(test_sph_initial_pressure ${LAHAR_TEST_DIR}/test_sph_initial_pressure.c)
target_link_libraries(test_sph_initial_pressure PRIVATE lahar_sph)
add_test(NAME sph_initial_pressure COMMAND test_sph_initial_pressure ${CMAKE_CURRENT_BINARY_DIR})
set_tests_properties(sph_initial_pressure PROPERTIES LABELS "fast;sph")

# Per-particle initial fields from an HDF5 file equal the same fields given as expressions
# (tests/sph_initial_file.sh; two runs of 625 particles for 0.04 s).
add_test(NAME sph_initial_file COMMAND sh ${LAHAR_TEST_DIR}/sph_initial_file.sh $<TARGET_FILE:lahar>
  ${CMAKE_SOURCE_DIR}/cases/taylor_green_2d.yaml ${CMAKE_CURRENT_BINARY_DIR}/sph_initial_file ${LAHAR_OUTPUT_PYTHON})
set_tests_properties(sph_initial_file PROPERTIES LABELS "fast;sph" TIMEOUT 120)
