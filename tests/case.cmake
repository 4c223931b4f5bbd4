# Case files, shapes and mass properties (common/io/case.c, common/geometry/shape_build.c).
add_executable(lahar-case-check ${LAHAR_TEST_DIR}/case_check_main.c)
target_link_libraries(lahar-case-check PRIVATE lahar_common)

add_executable(test_case ${LAHAR_TEST_DIR}/test_case.c)
target_link_libraries(test_case PRIVATE lahar_common)
# every case in cases/ loads; mass properties, principal frames, hulls and STL against analytic values
add_test(NAME case_shapes COMMAND test_case ${CMAKE_SOURCE_DIR}/cases ${CMAKE_CURRENT_BINARY_DIR})
set_tests_properties(case_shapes PROPERTIES LABELS fast)

add_executable(test_case_bad ${LAHAR_TEST_DIR}/test_case_bad.c)
target_link_libraries(test_case_bad PRIVATE lahar_common)
# one fixture per class of bad input: exit status 2, message names file, line and key
file(MAKE_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR}/case_bad_inputs)
add_test(NAME case_bad_inputs COMMAND test_case_bad $<TARGET_FILE:lahar-case-check> ${LAHAR_TEST_DIR}/bad_cases
  ${CMAKE_CURRENT_BINARY_DIR}/case_bad_inputs)
set_tests_properties(case_bad_inputs PROPERTIES LABELS fast)

add_executable(test_case_blocks ${LAHAR_TEST_DIR}/test_case_blocks.c)
target_link_libraries(test_case_blocks PRIVATE lahar_common)
# SPH particle blocks: polygon / STL fill against exact counts and analytic areas and volumes,
# bodies cut out of the lattice against an independent inside test
add_test(NAME case_blocks COMMAND test_case_blocks ${CMAKE_CURRENT_BINARY_DIR})
set_tests_properties(case_blocks PROPERTIES LABELS fast)

# the command line: bad option values and an unknown DEM engine exit 2 with a message naming the
# option, or the case's file, line and key
add_test(NAME cli_bad_args COMMAND sh ${LAHAR_TEST_DIR}/cli_bad_args.sh $<TARGET_FILE:lahar>
         ${LAHAR_TEST_DIR}/bad_args ${CMAKE_CURRENT_BINARY_DIR}/cli_bad_args)
set_tests_properties(cli_bad_args PROPERTIES LABELS fast)

# Ctrl-C / SIGTERM during a long set-up (555,000 particles) ends the run within 2 s, in-process and
# as processes (these in a private namespace: label netns)
add_test(NAME cli_interrupt_setup COMMAND sh ${LAHAR_TEST_DIR}/cli_interrupt.sh $<TARGET_FILE:lahar>
         ${CMAKE_SOURCE_DIR}/tools/case_override.py ${CMAKE_SOURCE_DIR}/cases ${CMAKE_CURRENT_BINARY_DIR}/cli_interrupt)
set_tests_properties(cli_interrupt_setup PROPERTIES LABELS "slow;netns" TIMEOUT 120)

# The key table (common/io/case_keys.c) drives the loader: keys accepted, defaults, range messages
add_executable(test_case_keys ${LAHAR_TEST_DIR}/test_case_keys.c)
target_link_libraries(test_case_keys PRIVATE lahar_common)
add_test(NAME case_keys COMMAND test_case_keys)
set_tests_properties(case_keys PROPERTIES LABELS fast)
# cases/reference.yaml is what `lahar keys --yaml` prints (regenerate: build/bin/lahar keys --yaml > cases/reference.yaml)
add_test(NAME case_reference_yaml COMMAND sh -c "\"$1\" keys --yaml | diff -u \"$2\" - && ! \"$1\" keys nosuchsection 2>/dev/null"
         sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/reference.yaml)
set_tests_properties(case_reference_yaml PROPERTIES LABELS fast)
