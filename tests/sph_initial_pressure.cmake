# sph.initial_pressure: hydrostatic block densities against the inverse EOS (linear, Tait).
lahar_test(sph_initial_pressure PROGRAM test_sph_initial_pressure SOURCES test_sph_initial_pressure.c
  LIBS lahar_sph ARGS ${CMAKE_CURRENT_BINARY_DIR} LABELS fast sph)

# Per-particle initial fields from an HDF5 file equal the same fields given as expressions
# (tests/sph_initial_file.sh; two runs of 625 particles for 0.04 s).
lahar_test(sph_initial_file COMMAND sh ${LAHAR_TEST_DIR}/sph_initial_file.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/taylor_green_2d.yaml ${CMAKE_CURRENT_BINARY_DIR}/sph_initial_file ${LAHAR_OUTPUT_PYTHON}
  LABELS fast sph TIMEOUT 120)
