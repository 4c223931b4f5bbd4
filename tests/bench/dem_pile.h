/* A settling pile of mixed sphero-polyhedra (spheres, boxes, 10-point hull rocks, as in
 * cases/dem_drop_3d.yaml) in a walled box, of any size: the scene of the DEM benchmark
 * (bench_dem) and of the no-allocation test (test_dem_noalloc). */
#ifndef LAHAR_DEM_PILE_H
#define LAHAR_DEM_PILE_H
#include "scene.h"

/* n free bodies on a lattice of `layers` layers (footprint ceil(sqrt(n/layers)) squared, spacing 8.5 cm,
 * a little more than the largest bounding diameter), random orientations and velocities up to 0.1 m/s, over a
 * floor and 4 walls. hertz = 0: linear kn = 2e5 N/m; 1: Hertz E = 1e8 Pa, nu = 0.25 (the drop
 * case's rock). e = 0.5, mu = 0.5. Deterministic for a given n and seed. Exits on failure. */
void dem_pile_case(lahar_case *c, int n, int layers, int hertz, unsigned seed);
/* The same pile of one kind of body only: 0 mixed (as dem_pile_case), 1 spheres, 2 boxes, 3 rocks. */
void dem_pile_case_kind(lahar_case *c, int n, int layers, int hertz, unsigned seed, int kind);

#endif
