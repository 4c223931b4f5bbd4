# Terrain (case section terrain:, common/terrain.h): fixed DEM surfaces from a 2D profile (CSV) and
# a 3D heightmap (ESRI ASCII grid). A disc on a 30 degree CSV profile (crossing two joints of the
# segment chain) and a sphere on a 30 degree .asc heightmap slide at g (sin - mu cos) within 1 %
# (`lahar check`, reference incline_roll). The parser errors are fixtures in bad_cases/terrain_*.
add_test(NAME terrain_disc_slide_2d
  COMMAND sh ${LAHAR_TEST_DIR}/validation_check.sh $<TARGET_FILE:lahar> ${LAHAR_TEST_DIR}/terrain/disc_slide_2d.yaml
          ${CMAKE_CURRENT_BINARY_DIR}/terrain/disc_slide_2d)
add_test(NAME terrain_sphere_slide_3d
  COMMAND sh ${LAHAR_TEST_DIR}/validation_check.sh $<TARGET_FILE:lahar> ${LAHAR_TEST_DIR}/terrain/sphere_slide_3d.yaml
          ${CMAKE_CURRENT_BINARY_DIR}/terrain/sphere_slide_3d)
set_tests_properties(terrain_disc_slide_2d terrain_sphere_slide_3d PROPERTIES LABELS "fast;terrain" TIMEOUT 300
  ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")
