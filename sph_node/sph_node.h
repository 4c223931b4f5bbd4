/* The SPH node's process loop (minimal for now: particles on a lattice falling under gravity, no
 * forces). Joins a run, creates the particles of the scene's blocks and answers each STEP of the
 * coordinator (protocol in lcm_types/README.md). Used by lahar-sph and `lahar run --in-process`. */
#ifndef LAHAR_SPH_NODE_H
#define LAHAR_SPH_NODE_H
#include <stdint.h>

typedef struct {
    const char *lcm_url; /* udpm://... or memq:// */
    int64_t run_id;      /* 0: join the first run announced */
    int threads;         /* OpenMP threads; 0 = OpenMP default */
    double join_wait_s;  /* how long to wait for the coordinator's HELLO */
} lahar_sph_node_options;

/* Particles as structure of arrays. */
typedef struct {
    int64_t n;
    double *x, *y, *z, *vx, *vy, *vz, *density, *pressure;
    int32_t *phase; /* 0 = fluid for now */
    int64_t *id;
} lahar_sph_particles;

/* Fill particles on the lattice of spacing dx in every block: centres at lo + (i + 1/2) dx for
 * i < floor((hi - lo) / dx + 1e-9) per axis (one layer at z = 0 in 2D). Returns the count, or -1
 * when out of memory. Release with lahar_sph_particles_free. */
int64_t lahar_sph_particles_create(lahar_sph_particles *p, int dim, double dx, double rest_density, int nblock,
                                   const double (*lo)[3], const double (*hi)[3], const double (*v)[3]);
void lahar_sph_particles_free(lahar_sph_particles *p);
/* Semi-implicit Euler under gravity: v += g dt, then x += v dt. */
void lahar_sph_particles_advance(lahar_sph_particles *p, const double g[3], double dt);
/* CFL-like step: 0.25 dx / (|v|max + sqrt(|g| dx)). */
double lahar_sph_particles_dt(const lahar_sph_particles *p, const double g[3], double dx);

int lahar_sph_node_run(const lahar_sph_node_options *o);

#endif
