# Periodic images of bodies in the SPH-DEM coupling (brief CYL): a body across a periodic boundary
# acts on the fluid as the same body in the middle of the period (2D fixed and free discs, 3D box),
# to round-off; without the images the corner disc loses most of its force.
add_executable(test_coupling_periodic ${LAHAR_TEST_DIR}/test_coupling_periodic.c)
target_link_libraries(test_coupling_periodic PRIVATE lahar_sph)
add_test(NAME coupling_periodic COMMAND test_coupling_periodic)
set_tests_properties(coupling_periodic PROPERTIES LABELS "fast;cyl" TIMEOUT 60)
