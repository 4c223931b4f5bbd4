# Periodic images of bodies in the SPH-DEM coupling: a body across a periodic boundary
# acts on the fluid as the same body in the middle of the period (2D fixed and free discs, 3D box),
# to round-off; without the images the corner disc loses most of its force.
lahar_test(coupling_periodic PROGRAM test_coupling_periodic SOURCES test_coupling_periodic.c
  LIBS lahar_sph LABELS fast cyl TIMEOUT 60)
