# Open boundaries of the SPH fluid (inlets, outlets, domain box): the library test is sph_inflow
# (tests/sph.cmake), resume checkpoint_inflow (tests/checkpoint.cmake); this is the example case
# end to end (tests/inflow_example.sh).
lahar_test(example_inflow_channel_2d
  COMMAND sh ${LAHAR_TEST_DIR}/inflow_example.sh $<TARGET_FILE:lahar> ${CMAKE_SOURCE_DIR}/cases/inflow_channel_2d.yaml
          ${CMAKE_CURRENT_BINARY_DIR}/example_inflow_channel_2d ${LAHAR_OUTPUT_PYTHON}
  LABELS fast TIMEOUT 300)
