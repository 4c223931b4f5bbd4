# DEM conformance suite (tests/dem_conformance/README.md): dem_conformance plays the coordinator
# and the SPH node against a DEM engine executable in a private network namespace (label netns)
# and certifies it. One test per engine; an engine the lahar-dem binary does not list is skipped.
add_executable(dem_conformance ${LAHAR_TEST_DIR}/dem_conformance/dem_conformance.c
                               ${LAHAR_TEST_DIR}/dem_conformance/conformance_session.c)
target_include_directories(dem_conformance PRIVATE ${LAHAR_TEST_DIR}/dem_conformance)
target_compile_definitions(dem_conformance PRIVATE
  LAHAR_CONFORMANCE_CASES="${LAHAR_TEST_DIR}/dem_conformance/cases")
target_link_libraries(dem_conformance PRIVATE lahar_common)

function(lahar_dem_conformance_test engine labels)
  add_test(NAME dem_conformance_${engine}
           COMMAND dem_conformance --engine ${engine} --work ${CMAKE_CURRENT_BINARY_DIR}/dem_conformance_${engine}
                   -- $<TARGET_FILE:lahar-dem>)
  set_tests_properties(dem_conformance_${engine} PROPERTIES LABELS "${labels}" TIMEOUT 180
                       SKIP_RETURN_CODE 77 REQUIRED_FILES "$<TARGET_FILE:lahar-dem>")
endfunction()
lahar_dem_conformance_test(spheropoly "fast;netns;conformance;dem")
# runs once lahar-dem lists the engine (built when liblammps-dev is present); skipped until then
lahar_dem_conformance_test(lammps "fast;netns;conformance;dem")
# the harness itself fails what it must fail: an executable that is no DEM engine, and an engine
# whose loads differ from what the harness expects (as if it ignored LOADS)
add_test(NAME dem_conformance_not_an_engine
         COMMAND dem_conformance --work ${CMAKE_CURRENT_BINARY_DIR}/dem_conformance_not_an_engine -- /bin/false)
set_tests_properties(dem_conformance_not_an_engine PROPERTIES LABELS "fast;netns;conformance" TIMEOUT 60
                     PASS_REGULAR_EXPRESSION "FAIL handshake[^\n]*exited \\(status 1\\)[^\n]*\n0 passed, 1 failed")
add_test(NAME dem_conformance_ignored_loads
         COMMAND dem_conformance --self-test ignore-loads --work ${CMAKE_CURRENT_BINARY_DIR}/dem_conformance_ignored_loads
                 -- $<TARGET_FILE:lahar-dem>)
set_tests_properties(dem_conformance_ignored_loads PROPERTIES LABELS "fast;netns;conformance" TIMEOUT 180
                     PASS_REGULAR_EXPRESSION "PASS step_status[^\n]*\nFAIL loads"
                     REQUIRED_FILES "$<TARGET_FILE:lahar-dem>")
