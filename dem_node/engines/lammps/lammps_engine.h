/* The LAMMPS DEM engine ("lammps"): free spheres (3D) and discs (2D) and fixed planes, driven
 * through the LAMMPS C library (liblammps). Built only when liblammps is found (LAHAR_HAVE_LAMMPS);
 * reached through lahar_dem_engine_find(). What it supports: dem_node/engines/lammps/README.md. */
#ifndef LAHAR_LAMMPS_ENGINE_H
#define LAHAR_LAMMPS_ENGINE_H
#include "dem_engine.h"

extern const lahar_dem_engine_ops lahar_dem_lammps_ops;

/* The normal damping coefficient LAMMPS' `damping tsuji` derives from the restitution it is given
 * (a polynomial fit in e, pair_style granular); exposed so the tests can check the inversion. */
double lahar_lammps_tsuji_alpha(double cor);

#endif
