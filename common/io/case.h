/* Case files: YAML (documented key by key in cases/dem_drop_3d.yaml) -> lahar_case (scene.h).
 *
 * The loader checks everything it can before a run starts: YAML syntax, unknown keys (with the
 * closest known key as a suggestion), types, ranges, references between sections, shapes
 * (degenerate or non-convex polyhedra, unreadable STL files) and bodies overlapping at t = 0.
 * It fills a default for every optional key, builds every shape, computes the mass properties of
 * free and prescribed bodies and moves their shapes into the principal frame. */
#ifndef LAHAR_CASE_H
#define LAHAR_CASE_H
#include "scene.h"
#include "shape_build.h"

/* Exit status of a program that rejects its input (lahar, lahar-case-check). */
#define LAHAR_EXIT_BAD_INPUT 2

/* Parse and validate a case file. On error prints ONE message to stderr of the form
 *   cases/x.yaml:12: bodies[3].radius: must be > 0 (got -0.1); <what to do>
 * and returns 2 (LAHAR_EXIT_BAD_INPUT); returns 0 on success. Nothing stays allocated on failure
 * and *out is zeroed. */
int lahar_case_load(const char *path, lahar_case *out);

/* Same, but the message goes to `err` (without a trailing newline) instead of stderr. */
int lahar_case_load_err(const char *path, lahar_case *out, char *err, size_t errlen);
/* Same, with the files the case references (STL, initial: file) relative to base_dir instead of
 * the case file's directory (NULL: the case file's): a copy of a case kept elsewhere
 * (`lahar resume`). */
int lahar_case_load_dir(const char *path, const char *base_dir, lahar_case *out, char *err, size_t errlen);
/* The same from the bytes of a case file in memory: `path` names it in messages and is where
 * relative paths in it (STL meshes, initial files) start from. lahar_case_load_err reads the file
 * and calls this. */
int lahar_case_load_mem(const char *path, const void *data, size_t size, lahar_case *out, char *err, size_t errlen);
/* The case file's absolute path into buf (for the records a run leaves, summary.json and
 * check.json, so that a tool run from another directory finds the case); the path as the case
 * holds it when that cannot be resolved (the file is gone, a case built in memory). Returns buf. */
const char *lahar_case_path_abs(const lahar_case *c, char *buf, size_t size);
/* Every sph: option at the default the loader gives it (the key table, case_keys.c), for programs
 * that build a solver without a case file; c0 and the halo, whose defaults depend on the case,
 * are 0. */
void lahar_sph_options_default(lahar_sph_options *o);

/* Release everything a loaded (or scene-message-built) case owns; the case is zeroed. Safe on a
 * zeroed case. */
void lahar_case_free(lahar_case *c);

/* Particles of block `block` at t = 0: the lattice points of lahar_particle_block_lattice
 * (shape_build.h) that lie outside every body, so water poured around a cylinder or under a
 * floating box leaves the bodies' room empty; a point within the coupling halo dx/2 of a free
 * body's surface is moved out to it, so no particle starts overlapping a body that it would kick
 * (case_lattice.c, case_lattice_cut). With sph.body_layers = N the lattice points within N dx of a sphere's
 * (disc's) surface are replaced by N layers concentric with it, appended after the lattice points
 * (case_lattice.c, case_block_layers). Writes the first `cap` points to out (NULL to
 * count) and returns how many there are, or -1 when out of memory. The SPH node fills its
 * particles with this (mass rho0 dx^D each, the block's velocity). */
int64_t lahar_case_block_lattice(const lahar_case *c, int block, double (*out)[3], int64_t cap);
/* The per-particle initial fields of block pb at its n lattice points pts (in the order of
 * lahar_case_block_lattice): from the expressions of the case keys velocity: / pressure:
 * (libmatheval) or from the datasets vx, vy, vz, pressure of its initial file (HDF5). v[i] = the
 * block's velocity with every given component replaced; p[i] = the pressure when the block gives
 * one (*has_p = 1; p untouched otherwise). 0, or -1 with a message naming the block and the
 * expression, or the file and the dataset (missing file, wrong size, not finite). */
int lahar_case_block_initial(const lahar_particle_block *pb, const double (*pts)[3], int64_t n, double (*v)[3],
                             double *p, int *has_p, char *err, size_t errlen);

/* 1 if the world point x lies in body b's solid at its stored pose: within the sweep radius of
 * the core, or inside a closed core (2D: a closed ring of vertices, polygons, boxes and closed
 * polylines alike; 3D: a convex polyhedron with >= 4 faces). */
int lahar_body_contains(const lahar_body *b, int dim, const double x[3]);

/* Index of the body / material called `name`, or -1. */
int lahar_case_find_body(const lahar_case *c, const char *name);
int lahar_case_find_material(const lahar_case *c, const char *name);

#endif
