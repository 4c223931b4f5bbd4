# HDF5/XDMF writers, the SWMR force stream, `lahar check` evaluation, tools/.
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
lahar_test(output_writers COMMAND test_output ${LAHAR_OUTPUT_TEST_DIR}/writers LABELS fast output TIMEOUT 120
  PROPERTIES FIXTURES_SETUP output_files)

lahar_test(output_xdmf COMMAND ${LAHAR_OUTPUT_PYTHON} ${LAHAR_TEST_DIR}/test_output_xdmf.py ${LAHAR_OUTPUT_TEST_DIR}/writers
  LABELS fast output TIMEOUT 60 PROPERTIES FIXTURES_REQUIRED output_files)

lahar_output_test(test_output_swmr)
lahar_test(output_swmr COMMAND test_output_swmr ${LAHAR_OUTPUT_TEST_DIR}/swmr LABELS fast output TIMEOUT 60)
lahar_test(output_swmr_h5py COMMAND ${LAHAR_OUTPUT_PYTHON} ${LAHAR_TEST_DIR}/test_output_swmr_h5py.py $<TARGET_FILE:test_output_swmr> ${LAHAR_OUTPUT_TEST_DIR}/swmr_h5py
  LABELS fast output TIMEOUT 60)

lahar_output_test(test_output_memory)
lahar_test(output_memory COMMAND test_output_memory ${LAHAR_OUTPUT_TEST_DIR}/memory LABELS fast output TIMEOUT 120
  PROPERTIES SKIP_RETURN_CODE 77)

lahar_output_test(test_check lahar_coord)
lahar_test(output_check COMMAND test_check ${LAHAR_OUTPUT_TEST_DIR}/check LABELS fast output TIMEOUT 120
  ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")

lahar_test(output_h5_compare COMMAND ${LAHAR_OUTPUT_PYTHON} ${LAHAR_TEST_DIR}/test_h5_compare.py ${LAHAR_OUTPUT_TEST_DIR}/h5_compare
  LABELS fast output TIMEOUT 60)

lahar_output_test(test_check_fluid lahar_coord)
lahar_test(output_check_fluid COMMAND test_check_fluid ${LAHAR_OUTPUT_TEST_DIR}/check_fluid LABELS fast output
  TIMEOUT 180 ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")

# End to end: the Poiseuille case (Trujillo-Vela et al. 2020 section 5.1, 20 particles across H) run in-process
# and evaluated by `lahar check` against its bounds (steady L2 <= 1 %, plate force <= 1 %).
# Measured: 0.28 % and 0.12 %, 4 s in Release.
lahar_test(check_poiseuille_2d COMMAND lahar check ${CMAKE_SOURCE_DIR}/cases/poiseuille_2d.yaml -o ${LAHAR_OUTPUT_TEST_DIR}/check_poiseuille_2d --in-process -q --overwrite
  LABELS slow output TIMEOUT 300 ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")

# tools/ as tools/README.md describes it: a row per script, executable, lahar_py.require() before
# the third-party imports (so a python3 without h5py/matplotlib re-runs them under /usr/bin/python3),
# `--help` exits 0
lahar_test(tools_readme COMMAND ${LAHAR_OUTPUT_PYTHON} ${LAHAR_TEST_DIR}/tools_check.py ${CMAKE_SOURCE_DIR}/tools
  LABELS fast output)
# tools/case_override.py's list paths: an element by name or index, a named element added by a map
# (a body the case does not have), the refusals (tests/tools_case_override.py)
lahar_test(tools_case_override COMMAND ${LAHAR_OUTPUT_PYTHON} ${LAHAR_TEST_DIR}/tools_case_override.py ${CMAKE_SOURCE_DIR}
  ${CMAKE_CURRENT_BINARY_DIR}/tools_case_override LABELS fast output)
# The impact tools on runs that end before the impact: plot_impact.py tabulates "none",
# compare_spheric2.py exits 2 with a message (both crashed with a Python traceback)
lahar_test(tools_no_impact COMMAND sh ${LAHAR_TEST_DIR}/tools_no_impact.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR} ${CMAKE_CURRENT_BINARY_DIR}/tools_no_impact ${LAHAR_OUTPUT_PYTHON}
  LABELS fast output TIMEOUT 120)
# The #include lines against the dependencies each folder's README states (tests/include_deps.py:
# e.g. common/ never includes from the nodes or the coordinator)
lahar_test(include_deps COMMAND ${LAHAR_OUTPUT_PYTHON} ${LAHAR_TEST_DIR}/include_deps.py ${CMAKE_SOURCE_DIR}
  LABELS fast output)
# Every <file>.md "<section>" reference in code, tests, cases and docs names a section that exists
# (tests/doc_section_refs.py): a section renamed or moved leaves no reader pointed at nothing
lahar_test(doc_section_refs COMMAND ${LAHAR_OUTPUT_PYTHON} ${LAHAR_TEST_DIR}/doc_section_refs.py ${CMAKE_SOURCE_DIR}
  LABELS fast output)

# A writer killed with SIGKILL at random moments (inside HDF5's writes and closes too) leaves
# bodies.h5 and particles.h5 that open, with every snapshot it had finished: 80 writers killed
# (tests/test_output_killed.c), 8 s
lahar_output_test(test_output_killed)
lahar_test(output_killed COMMAND test_output_killed ${LAHAR_OUTPUT_TEST_DIR}/killed 80 LABELS fast output TIMEOUT 120)

# The cost of a particle snapshot at 2,400 to 1,000,000 particles (tests/bench/bench_output.c),
# run by the `bench` target; prints a table, never a pass/fail (docs/bench/output.md).
add_executable(bench_output ${LAHAR_TEST_DIR}/bench/bench_output.c)
target_link_libraries(bench_output PRIVATE lahar_common)
add_custom_target(bench_output_table COMMAND bench_output ${CMAKE_BINARY_DIR}/bench_output_dir DEPENDS bench_output
  USES_TERMINAL COMMENT "bench_output: the cost of a particle snapshot")
add_dependencies(bench bench_output_table)

# A file system without renameat2's RENAME_EXCHANGE (a shim makes it fail): the snapshot files
# are written in place after one note each, bitwise as with the exchange; `output.twins: false`
# writes in place from the start, as processes (tests/output_no_exchange.sh).
# Not `fast`: the ASan build cannot preload a library ahead of its runtime.
add_library(renameat2_unsupported MODULE ${LAHAR_TEST_DIR}/renameat2_unsupported.c)
lahar_test(output_no_exchange COMMAND sh ${LAHAR_TEST_DIR}/output_no_exchange.sh $<TARGET_FILE:lahar>
  $<TARGET_FILE:renameat2_unsupported> ${CMAKE_SOURCE_DIR} ${CMAKE_CURRENT_BINARY_DIR}/output_no_exchange ${LAHAR_OUTPUT_PYTHON}
  LABELS output netns TIMEOUT 120)
