# Case files, shapes and mass properties (common/io/case*.c, common/geometry/shape_*.c).
add_executable(lahar-case-check ${LAHAR_TEST_DIR}/case_check_main.c)
target_link_libraries(lahar-case-check PRIVATE lahar_common)

add_executable(test_case ${LAHAR_TEST_DIR}/test_case.c)
target_link_libraries(test_case PRIVATE lahar_common)
# every case in cases/ loads; mass properties, principal frames, hulls and STL against analytic values
lahar_test(case_shapes COMMAND test_case ${CMAKE_SOURCE_DIR}/cases ${CMAKE_CURRENT_BINARY_DIR} LABELS fast)

add_executable(test_case_bad ${LAHAR_TEST_DIR}/test_case_bad.c)
target_link_libraries(test_case_bad PRIVATE lahar_common)
# one fixture per class of bad input: exit status 2, message names file, line and key
file(MAKE_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR}/case_bad_inputs)
lahar_test(case_bad_inputs COMMAND test_case_bad $<TARGET_FILE:lahar-case-check> ${LAHAR_TEST_DIR}/bad_cases ${CMAKE_CURRENT_BINARY_DIR}/case_bad_inputs
  LABELS fast)

add_executable(test_case_blocks ${LAHAR_TEST_DIR}/test_case_blocks.c)
target_link_libraries(test_case_blocks PRIVATE lahar_common)
# SPH particle blocks: polygon / STL fill against exact counts and analytic areas and volumes,
# bodies cut out of the lattice against an independent inside test
lahar_test(case_blocks COMMAND test_case_blocks ${CMAKE_CURRENT_BINARY_DIR} LABELS fast)

# the command line: bad option values and an unknown DEM engine exit 2 with a message naming the
# option, or the case's file, line and key
lahar_test(cli_bad_args COMMAND sh ${LAHAR_TEST_DIR}/cli_bad_args.sh $<TARGET_FILE:lahar> ${LAHAR_TEST_DIR}/bad_args ${CMAKE_CURRENT_BINARY_DIR}/cli_bad_args
  LABELS fast)

# Ctrl-C / SIGTERM during a long set-up (555,000 particles) ends the run within 2 s, in-process and
# as processes (these in a private namespace: label netns)
lahar_test(cli_interrupt_setup COMMAND sh ${LAHAR_TEST_DIR}/cli_interrupt.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/tools/case_override.py ${CMAKE_SOURCE_DIR}/cases ${CMAKE_CURRENT_BINARY_DIR}/cli_interrupt
  LABELS slow netns TIMEOUT 120)
# Progress into a log file or a pipe: whole lines every --progress-every s, none with -q / 0 / a
# short run at the default 60 s, a bad value refused (tests/cli_progress.sh)
lahar_test(cli_progress_log COMMAND sh ${LAHAR_TEST_DIR}/cli_progress.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/tools/case_override.py ${CMAKE_SOURCE_DIR}/cases ${CMAKE_CURRENT_BINARY_DIR}/cli_progress
  LABELS fast netns TIMEOUT 120)

# A box block whose sides are not multiples of sph.dx: `lahar validate` notes what its lattice fills
# (SPHERIC's column 1.228 x 1 x 0.55 m at dx 0.04: 1.2 x 1 x 0.52 m, 30 x 25 x 13 = 9750 particles,
# 92.4 %) and the dx that fills each short side; a case whose blocks are filled gets no note
lahar_test(cli_block_fill_note COMMAND sh -c "out=$(\"$1\" validate \"$2\") && echo \"$out\" && echo \"$out\" | grep -q '^  9750 particles' && echo \"$out\" | grep -q \"note: sph.blocks\\[0\\] 'column' is 1.228 x 1 x 0.55 m, but at dx = 0.04 its particles fill 1.2 x 1 x 0.52 m, 92.4 % of its volume\" && echo \"$out\" | grep -q 'x 1.228 = 31 x 0.039613, z 0.55 = 14 x 0.039286' && ! \"$1\" validate \"$3\" | grep note" sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/dam_break_obstacle_3d.yaml ${CMAKE_SOURCE_DIR}/cases/dam_break_lobovsky_2d.yaml
  LABELS fast)
# Pressure probes on a body with the penalty wall alone (debris_flow_3d.yaml's three on the dam)
# read far below the body's load: `lahar validate` notes it once, naming the first probe, and
# says which settings to use; a case with ghost walls (jet_impingement_2d.yaml) gets no note
lahar_test(cli_wall_probe_note COMMAND sh -c "out=$(\"$1\" validate \"$2\") && echo \"$out\" && echo \"$out\" | grep -q \"note: probes\\[0\\] 'dam_low' (and the other probes on bodies) reads the pressure on body 'dam'\" && echo \"$out\" | grep -q 'Set sph.wall_pressure: ghost and sph.penalty_stiffness: acoustic' && [ $(echo \"$out\" | grep -c 'note: probes') -eq 1 ] && ! \"$1\" validate \"$3\" | grep note" sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/debris_flow_3d.yaml ${CMAKE_SOURCE_DIR}/cases/jet_impingement_2d.yaml
  LABELS fast)

# The key table (common/io/case_keys.c) drives the loader: keys accepted, defaults, range messages
lahar_test(case_keys PROGRAM test_case_keys SOURCES test_case_keys.c LABELS fast)
# cases/reference.yaml is what `lahar keys --yaml` prints (regenerate: build/bin/lahar keys --yaml > cases/reference.yaml)
lahar_test(case_reference_yaml COMMAND sh -c "\"$1\" keys --yaml | diff -u \"$2\" - && ! \"$1\" keys nosuchsection 2>/dev/null" sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/reference.yaml
  LABELS fast)
# What `lahar keys` tells a user: every key with a default and a whole description (parentheses
# balanced: a description cut at a "; " inside one lost its half), `lahar keys SECTION` for every
# section, and every key written in cases/*.yaml listed there for its section
lahar_test(case_keys_doc COMMAND ${LAHAR_TEST_PYTHON} ${LAHAR_TEST_DIR}/case_keys_doc.py $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases
  LABELS fast)
