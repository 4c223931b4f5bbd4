# The README's default example (cases/debris_2d.yaml: a dam-break surge carrying boulders into a
# check dam) end to end at a shorter end time, with physical assertions on its output and the
# snapshot viewer (tests/example_debris.sh says what is asserted and why).
lahar_test(example_debris_2d COMMAND sh ${LAHAR_TEST_DIR}/example_debris.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/debris_2d.yaml ${CMAKE_CURRENT_BINARY_DIR}/example_debris_2d ${LAHAR_OUTPUT_PYTHON}
  LABELS slow TIMEOUT 900)
