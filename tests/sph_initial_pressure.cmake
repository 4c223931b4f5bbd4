# sph.initial_pressure (brief M): hydrostatic block densities against the inverse EOS (linear, Tait).
add_executable(test_sph_initial_pressure ${LAHAR_TEST_DIR}/test_sph_initial_pressure.c)
target_link_libraries(test_sph_initial_pressure PRIVATE lahar_sph)
add_test(NAME sph_initial_pressure COMMAND test_sph_initial_pressure ${CMAKE_CURRENT_BINARY_DIR})
set_tests_properties(sph_initial_pressure PROPERTIES LABELS "fast;sph")
