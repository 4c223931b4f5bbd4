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
    lahar_test(dem_conformance_${engine} COMMAND dem_conformance --engine ${engine} --work ${CMAKE_CURRENT_BINARY_DIR}/dem_conformance_${engine} -- $<TARGET_FILE:lahar-dem>
    LABELS ${labels} TIMEOUT 180 PROPERTIES SKIP_RETURN_CODE 77 REQUIRED_FILES "$<TARGET_FILE:lahar-dem>")
endfunction()
lahar_dem_conformance_test(spheropoly "fast;netns;conformance;dem")
# runs once lahar-dem lists the engine (built when liblammps-dev is present); skipped until then
lahar_dem_conformance_test(lammps "fast;netns;conformance;dem")
# the harness itself fails what it must fail: an executable that is no DEM engine, and an engine
# whose loads differ from what the harness expects (as if it ignored LOADS)
lahar_test(dem_conformance_not_an_engine COMMAND dem_conformance --work ${CMAKE_CURRENT_BINARY_DIR}/dem_conformance_not_an_engine -- /bin/false
  LABELS fast netns conformance TIMEOUT 60 PROPERTIES PASS_REGULAR_EXPRESSION "FAIL handshake[^\n]*exited \\(status 1\\)[^\n]*\n0 passed, 1 failed")
lahar_test(dem_conformance_ignored_loads COMMAND dem_conformance --self-test ignore-loads --work ${CMAKE_CURRENT_BINARY_DIR}/dem_conformance_ignored_loads -- $<TARGET_FILE:lahar-dem>
  LABELS fast netns conformance TIMEOUT 180
  PROPERTIES PASS_REGULAR_EXPRESSION "PASS step_status[^\n]*\nFAIL loads" REQUIRED_FILES "$<TARGET_FILE:lahar-dem>")
