# The LAMMPS DEM engine (dem.engine: lammps), built into lahar_dem when Debian's liblammps-dev is
# installed (pkg-config liblammps). Without it the rest builds and tests/dem_lammps.cmake skips.
pkg_check_modules(LAMMPS IMPORTED_TARGET liblammps)
if(LAMMPS_FOUND)
  target_sources(lahar_dem PRIVATE ${CMAKE_CURRENT_LIST_DIR}/lammps_engine.c)
  target_include_directories(lahar_dem PUBLIC ${CMAKE_CURRENT_LIST_DIR})
  target_compile_definitions(lahar_dem PUBLIC LAHAR_HAVE_LAMMPS)
  target_link_libraries(lahar_dem PUBLIC PkgConfig::LAMMPS)
  message(STATUS "lahar: LAMMPS engine: built (liblammps ${LAMMPS_VERSION})")
  set(LAHAR_HAVE_LAMMPS ON)
else()
  message(STATUS "lahar: LAMMPS engine: not built (install liblammps-dev)")
  set(LAHAR_HAVE_LAMMPS OFF)
endif()
