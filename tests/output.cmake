# HDF5/XDMF writers, the SWMR force stream, `lahar check` evaluation, tools/ (brief D).
# Python parts need python3 with h5py/numpy (Debian's python3-h5py): prefer /usr/bin/python3,
# where Debian installs them (tools/*.py also re-exec themselves there when h5py is missing).
set(LAHAR_OUTPUT_TEST_DIR ${CMAKE_BINARY_DIR}/test_output_data)
file(MAKE_DIRECTORY ${LAHAR_OUTPUT_TEST_DIR})

# lahar_output_test(NAME [LIBRARY]): the library defaults to lahar_common; `lahar check`'s
# evaluators live in the coordinator (coordinator/check/), so their tests link lahar_coord.
function(lahar_output_test name)
  set(lib lahar_common)
  if(ARGC GREATER 1)
    set(lib ${ARGV1})
  endif()
  add_executable(${name} ${LAHAR_TEST_DIR}/${name}.c)
  target_link_libraries(${name} PRIVATE ${lib})
endfunction()

lahar_output_test(test_output)
add_test(NAME output_writers COMMAND test_output ${LAHAR_OUTPUT_TEST_DIR}/writers)
set_tests_properties(output_writers PROPERTIES LABELS "fast;output" TIMEOUT 120
  FIXTURES_SETUP output_files)

add_test(NAME output_xdmf COMMAND ${LAHAR_OUTPUT_PYTHON} ${LAHAR_TEST_DIR}/test_output_xdmf.py
  ${LAHAR_OUTPUT_TEST_DIR}/writers)
set_tests_properties(output_xdmf PROPERTIES LABELS "fast;output" TIMEOUT 60
  FIXTURES_REQUIRED output_files)

lahar_output_test(test_output_swmr)
add_test(NAME output_swmr COMMAND test_output_swmr ${LAHAR_OUTPUT_TEST_DIR}/swmr)
set_tests_properties(output_swmr PROPERTIES LABELS "fast;output" TIMEOUT 60)
add_test(NAME output_swmr_h5py COMMAND ${LAHAR_OUTPUT_PYTHON} ${LAHAR_TEST_DIR}/test_output_swmr_h5py.py
  $<TARGET_FILE:test_output_swmr> ${LAHAR_OUTPUT_TEST_DIR}/swmr_h5py)
set_tests_properties(output_swmr_h5py PROPERTIES LABELS "fast;output" TIMEOUT 60)

lahar_output_test(test_check lahar_coord)
add_test(NAME output_check COMMAND test_check ${LAHAR_OUTPUT_TEST_DIR}/check)
set_tests_properties(output_check PROPERTIES LABELS "fast;output" TIMEOUT 120
  ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")

add_test(NAME output_h5_compare COMMAND ${LAHAR_OUTPUT_PYTHON} ${LAHAR_TEST_DIR}/test_h5_compare.py
  ${LAHAR_OUTPUT_TEST_DIR}/h5_compare)
set_tests_properties(output_h5_compare PROPERTIES LABELS "fast;output" TIMEOUT 60)

lahar_output_test(test_check_fluid lahar_coord)
add_test(NAME output_check_fluid COMMAND test_check_fluid ${LAHAR_OUTPUT_TEST_DIR}/check_fluid)
set_tests_properties(output_check_fluid PROPERTIES LABELS "fast;output" TIMEOUT 180
  ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")

# End to end: the Poiseuille case (Trujillo-Vela et al. 2020 section 5.1, 20 particles across H) run in-process
# and evaluated by `lahar check` against its bounds (steady L2 <= 1 %, plate force <= 1 %).
# Measured: 0.28 % and 0.12 %, 4 s in Release.
add_test(NAME check_poiseuille_2d COMMAND lahar check ${CMAKE_SOURCE_DIR}/cases/poiseuille_2d.yaml
  -o ${LAHAR_OUTPUT_TEST_DIR}/check_poiseuille_2d --in-process -q --overwrite)
set_tests_properties(check_poiseuille_2d PROPERTIES LABELS "slow;output" TIMEOUT 300
  ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")
