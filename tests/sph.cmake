# SPH solver core: kernels (common/kernels/kernel.c), particles, cell lists, WCSPH and the
# SPH-DEM coupling (sph_node/sph_*.c), tested at library level without processes.
lahar_test(sph_kernel PROGRAM test_kernel SOURCES test_kernel.c LABELS fast sph)

lahar_test(sph_poiseuille PROGRAM test_sph_poiseuille SOURCES test_sph_poiseuille.c
  LIBS lahar_sph LABELS fast sph TIMEOUT 300)

lahar_test(sph_fluid PROGRAM test_sph_fluid SOURCES test_sph_fluid.c
  LIBS lahar_sph LABELS fast sph TIMEOUT 120)

# The Riemann scheme (sph.scheme: riemann, Zhang, Hu & Adams 2017): the pair's interface state against the
# acoustic characteristics, the limiter, and a water hammer at rho0 c0 U with both schemes.
lahar_test(sph_riemann PROGRAM test_sph_riemann SOURCES test_sph_riemann.c LIBS lahar_sph LABELS fast sph TIMEOUT 120)

lahar_test(sph_coupling PROGRAM test_sph_coupling SOURCES test_sph_coupling.c
  LIBS lahar_sph LABELS fast sph TIMEOUT 120)

lahar_test(sph_hydrostatic PROGRAM test_sph_hydrostatic SOURCES test_sph_hydrostatic.c test_bodies.c
  LIBS lahar_sph LABELS fast sph TIMEOUT 120)

lahar_test(sph_hydrostatic3d PROGRAM test_sph_hydrostatic3d SOURCES test_sph_hydrostatic3d.c test_bodies.c
  LIBS lahar_sph ARGS 10 3 ghost LABELS slow sph TIMEOUT 600)

lahar_test(sph_couette PROGRAM test_sph_couette SOURCES test_sph_couette.c
  LIBS lahar_sph LABELS fast sph TIMEOUT 120)

# SPS turbulence: nu_t of a uniform shear, zero force of a constant stress, a shear wave
# against the analytic divergence, a dam break that stays stable.
lahar_test(sph_sps PROGRAM test_sph_sps SOURCES test_sph_sps.c test_bodies.c LIBS lahar_sph LABELS fast sph TIMEOUT 120)

# Split step: step_begin + step_end integrate at second order in time (observed order at dt, dt/2, dt/4).
lahar_test(sph_split PROGRAM test_sph_split SOURCES test_sph_split.c test_bodies.c
  LIBS lahar_sph LABELS fast sph TIMEOUT 180 ENVIRONMENT "OMP_NUM_THREADS=2")

# Open boundaries (sph_node/inflow/sph_inflow.h): discharge through an inlet against the Gumbel
# hydrograph (Trujillo-Vela et al. 2020, eq. 36), a CSV t,Q table and a level table t,h, a 3D
# inlet, mass balance, outflow counts, unique ids, the capacity error, a supercritical channel at
# its steady depth, saturated soil and water leaving through an outlet and the domain box (removed
# and counted with their mass per phase).
lahar_test(sph_inflow PROGRAM test_sph_inflow SOURCES test_sph_inflow.c test_bodies.c LIBS lahar_sph LABELS fast sph TIMEOUT 300)
