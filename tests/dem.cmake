# DEM engine and geometry tests (brief A). `fast` ones also run under the sanitizers in CI.
function(lahar_dem_test name label)
  add_executable(${name} ${LAHAR_TEST_DIR}/${name}.c ${LAHAR_TEST_DIR}/dem_test_util.c)
  target_include_directories(${name} PRIVATE ${LAHAR_TEST_DIR})
  target_link_libraries(${name} PRIVATE lahar_dem)
  add_test(NAME ${name} COMMAND ${name})
  set_tests_properties(${name} PROPERTIES LABELS "${label};dem" TIMEOUT 300)
endfunction()

lahar_dem_test(test_geometry fast)
lahar_dem_test(test_dem_bounce fast)
lahar_dem_test(test_dem_incline fast)
lahar_dem_test(test_dem_slide fast)
lahar_dem_test(test_dem_freebody fast)
