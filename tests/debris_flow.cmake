# The debris flow of Trujillo-Vela et al. 2020 §6 (cases/debris_flow_2d.yaml: saturated soil, water,
# three disc boulders, a Gumbel inlet on the Yangbaodi terrain) on a coarse, short variant (dx = 1 m,
# 5 s; about 10 s on 2 cores): `lahar check` (reference landslide: no soil particle through the
# terrain, the soil's count kept), then tests/debris_flow_check.py on the output: mass balance of the
# inlet (entered - removed = change in the domain, 1e-12), no water through the terrain, pore
# pressure in the soil (p = a rho_w g d, a in [0.4, 1.2]), the particle count at the start within 5 %
# of the paper's 7662 scaled by (0.5 / 1)^2, the inlet's volume against eq. 36's integral up to 5 s;
# the end count (8216 scaled) only for a run to 30 s and the boulders' constant E_P on the flat only
# when they reach it (the full 30 s run: docs/bench/debris_flow.md).
lahar_test(debris_flow_2d
  COMMAND sh -c "sh '${LAHAR_TEST_DIR}/validation_check.sh' '$<TARGET_FILE:lahar>' '${CMAKE_SOURCE_DIR}/cases/debris_flow_2d.yaml' '${CMAKE_CURRENT_BINARY_DIR}/debris_flow/debris_flow_2d' dx=1.0 end=5 threads=2 && '${LAHAR_TEST_PYTHON}' '${LAHAR_TEST_DIR}/debris_flow_check.py' '${CMAKE_CURRENT_BINARY_DIR}/debris_flow/debris_flow_2d/run'"
  LABELS slow validation terrain TIMEOUT 300
  ENVIRONMENT LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON})

# The 3D showcase (cases/debris_flow_3d.yaml: saturated soil, water and four sphere boulders in a
# channel cut into a heightmap, hitting a check dam) on a coarse, short variant (dx = 0.4 m, 1320
# particles, 1.6 s: the front reaches the dam at about 1.15 s; 26 CPU-s, 2.5 min wall at load 10-14): `lahar check` (reference
# dam_break: the particle count kept, no particle inside the dam, a boulder or the terrain's swept
# layer), then tests/debris_flow_3d_check.py: no particle below the heightmap's surface at any
# snapshot, the domain's mass unchanged to 1e-12, the dam loaded, the x-momentum of the flow equal
# to minus the impulse of the dam's and the terrain's forces within 2 %, the lowest probe's peak
# between the stagnation pressure and 2 x the Joukowsky pressure rho_w c0 u of the arriving flow
# (0.96 x here; 0.82, 1.35 and 0.37 x at dx = 0.3, 0.2 and 0.1 m: docs/bench/debris_flow_3d.md).
lahar_test(debris_flow_3d
  COMMAND sh -c "sh '${LAHAR_TEST_DIR}/validation_check.sh' '$<TARGET_FILE:lahar>' '${CMAKE_SOURCE_DIR}/cases/debris_flow_3d.yaml' '${CMAKE_CURRENT_BINARY_DIR}/debris_flow/debris_flow_3d' dx=0.4 end=1.6 threads=2 && '${LAHAR_TEST_PYTHON}' '${LAHAR_TEST_DIR}/debris_flow_3d_check.py' '${CMAKE_CURRENT_BINARY_DIR}/debris_flow/debris_flow_3d/run'"
  LABELS slow validation terrain TIMEOUT 900
  ENVIRONMENT LAHAR_PYTHON=${LAHAR_OUTPUT_PYTHON})
