# The debris flow of Trujillo-Vela et al. 2020 §6 (cases/debris_flow_2d.yaml: saturated soil, water,
# three disc boulders, a Gumbel inlet on the Yangbaodi terrain) on a coarse, short variant (dx = 1 m,
# 5 s; about 10 s on 2 cores): `lahar check` (reference landslide: no soil particle through the
# terrain, the soil's count kept), then tests/debris_flow_check.py on the output: mass balance of the
# inlet (entered - removed = change in the domain, 1e-12), no water through the terrain, pore
# pressure in the soil (p = a rho_w g d, a in [0.4, 1.2]), the particle count at the start within 5 %
# of the paper's 7662 scaled by (0.5 / 1)^2, the inlet's volume against eq. 36's integral up to 5 s;
# the end count (8216 scaled) only for a run to 30 s and the boulders' constant E_P on the flat only
# when they reach it (the full 30 s run: cases/README.md "Debris flow").
lahar_test(debris_flow_2d
  COMMAND sh -c "sh '${LAHAR_TEST_DIR}/validation_check.sh' '$<TARGET_FILE:lahar>' '${CMAKE_SOURCE_DIR}/cases/debris_flow_2d.yaml' '${CMAKE_CURRENT_BINARY_DIR}/debris_flow/debris_flow_2d' dx=1.0 end=5 threads=2 && '${LAHAR_TEST_PYTHON}' '${LAHAR_TEST_DIR}/debris_flow_check.py' '${CMAKE_CURRENT_BINARY_DIR}/debris_flow/debris_flow_2d/run'"
  LABELS slow validation terrain TIMEOUT 300
  ENVIRONMENT LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON})
