# Terrain (case section terrain:, common/io/terrain.h): fixed DEM surfaces from a 2D profile (CSV) and
# a 3D heightmap (ESRI ASCII grid). A disc on a 30 degree CSV profile (crossing two joints of the
# segment chain) and a sphere on a 30 degree .asc heightmap slide at g (sin - mu cos) within 1 %
# (`lahar check`, reference incline_roll). The parser errors are fixtures in bad_cases/terrain_*.
lahar_test(terrain_disc_slide_2d
  COMMAND $<TARGET_FILE:lahar> check ${LAHAR_TEST_DIR}/terrain/disc_slide_2d.yaml
          -o ${CMAKE_CURRENT_BINARY_DIR}/terrain/disc_slide_2d --in-process -q --overwrite
  LABELS fast terrain TIMEOUT 300 ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")
lahar_test(terrain_sphere_slide_3d
  COMMAND $<TARGET_FILE:lahar> check ${LAHAR_TEST_DIR}/terrain/sphere_slide_3d.yaml
          -o ${CMAKE_CURRENT_BINARY_DIR}/terrain/sphere_slide_3d --in-process -q --overwrite
  LABELS fast terrain TIMEOUT 300 ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")

# Body energies in forces.h5 (dataset energy: E_P, E_K of Trujillo-Vela et al. 2020 eq. 37-38 and the
# rotational E_R): a spinning disc falling freely for 0.5 s against the closed form (to 1e-9).
lahar_test(terrain_body_energy_2d COMMAND sh -c "\"$1\" run \"$2\" -o \"$3\" --in-process -q --overwrite && \"$4\" \"$5\" \"$3\"" sh $<TARGET_FILE:lahar> ${LAHAR_TEST_DIR}/terrain/falling_disc_2d.yaml ${CMAKE_CURRENT_BINARY_DIR}/terrain/falling_disc_2d ${LAHAR_TEST_PYTHON} ${LAHAR_TEST_DIR}/terrain/body_energy_check.py
  LABELS fast terrain TIMEOUT 120)

# Trackers and control volumes (gauges.h5, sph_node/probes/sph_gauges.h): a water block translating
# uniformly without gravity, with a free disc riding above it at the same speed; the tracker
# follows x = x0 + t, the control volumes hold the closed-form mass, kinetic energy (Trujillo-Vela
# et al. 2020 eq. 39, the disc's included) and mass flux (tests/terrain/gauges_check.py).
# Run as separate processes, so the scene message carries the new probe fields.
lahar_test(terrain_gauges_uniform_2d COMMAND sh -c "\"$1\" run \"$2\" -o \"$3\" -q --overwrite && \"$4\" \"$5\" \"$3\"" sh $<TARGET_FILE:lahar> ${LAHAR_TEST_DIR}/terrain/gauges_uniform_2d.yaml ${CMAKE_CURRENT_BINARY_DIR}/terrain/gauges_uniform_2d ${LAHAR_TEST_PYTHON} ${LAHAR_TEST_DIR}/terrain/gauges_check.py
  LABELS fast terrain netns TIMEOUT 120)

# Regions between the terrain and an upper surface (sph.blocks[i].between): the lattice fills a
# flat slab exactly, dx/2 clear of the terrain's surface (2D profile: 540 particles; 3D heightmaps:
# 2700), counted by `lahar validate`.
foreach(name between_2d between_3d)
  if(name STREQUAL "between_2d")
    set(count 540)
  else()
    set(count 2700)
  endif()
    lahar_test(terrain_${name} COMMAND sh -c "\"$1\" validate \"$2\" | grep -q \"^  $3 particles \"" sh $<TARGET_FILE:lahar> ${LAHAR_TEST_DIR}/terrain/${name}.yaml ${count}
    LABELS fast terrain TIMEOUT 60)
endforeach()

# The Yangbaodi landslide (cases/yangbaodi_2d.yaml, Trujillo-Vela et al. 2020 5.4) at a CI
# resolution (dx = 0.76 m, 840 particles, the whole 30 s; 13 s on 2 cores): nothing through the
# terrain, no particle lost, the deposit's length within 30 % of the field's 140 m (here 172.5 m,
# +23 %) and its thickness within the field's 1-5 m (`lahar check`, reference landslide). The full
# case (dx = 0.38 m, 6 min on 2 cores) is run by hand; its numbers are in docs/bench/validation.md
# ("Yangbaodi landslide").
lahar_test(terrain_yangbaodi_2d COMMAND sh ${LAHAR_TEST_DIR}/validation_check.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/yangbaodi_2d.yaml ${CMAKE_CURRENT_BINARY_DIR}/terrain/yangbaodi_2d dx=0.76 threads=2
  LABELS slow validation terrain TIMEOUT 900 ENVIRONMENT "LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON}")

# Trackers, control volumes and body energies continue bitwise across `lahar resume`.
lahar_test(terrain_gauges_resume_2d COMMAND sh ${LAHAR_TEST_DIR}/terrain/resume_check.sh $<TARGET_FILE:lahar> ${LAHAR_TEST_PYTHON} ${CMAKE_SOURCE_DIR} ${CMAKE_CURRENT_BINARY_DIR}/terrain/gauges_resume_2d
  LABELS fast terrain checkpoint TIMEOUT 120)
