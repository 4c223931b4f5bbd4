/* SPH particles of the solver core as a structure of arrays, and their cell lists.
 *
 * Particles are kept sorted by cell (counting sort of the cell index, all arrays permuted, ids kept)
 * so that the neighbours of a particle are contiguous runs of memory. Cells are cubes of side >= the
 * kernel support; periodic axes use the domain box exactly (positions wrapped into [lo, hi)), the
 * other axes follow the particles (bounding box recomputed at every sort). All storage is allocated
 * at setup; the cell table grows by doubling on the rare sort that needs more cells. */
#ifndef LAHAR_SPH_PARTICLES_H
#define LAHAR_SPH_PARTICLES_H
#include <stdint.h>

/* OpenMP loops over particles run in parallel only above these counts: below them a step costs
 * more in barriers than in work (measured: 25 ms per step for 250 particles on a loaded 2-core
 * machine). Heavy = neighbour or body sums per particle, light = a few flops per particle. */
#define SPH_OMP_MIN_HEAVY 2048
#define SPH_OMP_MIN_LIGHT 32768

#define SPH_NSTRESS 6 /* symmetric tensor components xx, xy, xz, yy, yz, zz */

typedef struct {
    int64_t n, cap;
    /* state */
    double *x, *y, *z, *vx, *vy, *vz, *rho, *p, *m;
    /* rates (filled by sph_fluid_rates) */
    double *ax, *ay, *az, *drho;
    /* half-step state of the integrator */
    double *vhx, *vhy, *vhz, *rhoh;
    int32_t *phase; /* 0 = water, 1 = soil (sph_soil.h) */
    int64_t *id;    /* stable across sorts */
    /* soil only (NULL until sph_particles_alloc_stress; a water-only scene never allocates them):
     * effective stress sigma (xx, xy, xz, yy, yz, zz; Pa, tension positive) and its half-step
     * value of the integrator, permuted by the sort like every other particle array */
    double *sig[SPH_NSTRESS], *sigh[SPH_NSTRESS];
    /* sort scratch */
    double *scratch_d;
    int64_t *scratch_i;
    int32_t *scratch_p;
} sph_particles;

/* Allocate room for cap particles (n = 0). Returns 0 or -1 (out of memory; nothing allocated). */
int sph_particles_init(sph_particles *p, int64_t cap);
void sph_particles_free(sph_particles *p);
/* Allocate the soil stress arrays (sig, sigh) for cap particles, zeroed; no-op when present.
 * Returns 0 or -1 (out of memory; none allocated). */
int sph_particles_alloc_stress(sph_particles *p);
/* Append one particle at rest density rho with mass m; returns its index, or -1 when full. */
int64_t sph_particles_add(sph_particles *p, const double x[3], const double v[3], double m, double rho,
                          int32_t phase);
/* Append the lattice of spacing dx filling [lo, hi): centres lo + (i + 1/2) dx, floor((hi - lo)/dx)
 * per axis (z = 0 and one layer in 2D), mass rho dx^D, velocity v. Returns the number added or -1
 * when it does not fit (nothing added). */
int64_t sph_particles_add_box(sph_particles *p, int dim, double dx, double rho, const double lo[3], const double hi[3],
                              const double v[3]);

/* Cell lists. */
typedef struct {
    int dim;
    int periodic[3];
    double lo[3], hi[3];   /* domain: exact on periodic axes, particle bounds elsewhere */
    double size[3];        /* cell side per axis (>= min_size) */
    double min_size;       /* kernel support */
    int nc[3];             /* cells per axis */
    int64_t ncell, ncell_cap;
    int64_t *start;        /* ncell + 1: particles of cell c are start[c] .. start[c+1] - 1 */
    int64_t *count;        /* ncell_cap counters for the counting sort */
    int64_t *cell_of;      /* per particle (cap) */
    int64_t *perm;         /* per particle (cap) */
    int64_t pcap;
} sph_cells;

/* Cells of side >= support. Periodic axes: periodic[a] = 1 with [lo[a], hi[a]) the period, which
 * must hold >= 3 cells. Returns 0, or -1 (bad arguments, message in err, or out of memory). */
int sph_cells_init(sph_cells *c, int dim, double support, const int periodic[3], const double lo[3],
                   const double hi[3], int64_t particle_cap, char *err, int errlen);
void sph_cells_free(sph_cells *c);
/* Wrap positions on periodic axes, bin the particles and permute every particle array into cell
 * order (stable: particles of a cell keep their relative order). Returns 0, or -1 when the cell
 * table cannot grow (out of memory). */
int sph_cells_sort(sph_cells *c, sph_particles *p);
/* Cell coordinate of a position along axis a (clamped into the grid). */
static inline int sph_cells_coord(const sph_cells *c, int a, double x)
{
    double t = (x - c->lo[a]) / c->size[a];
    int i = t >= 0.0 ? (t < (double)c->nc[a] ? (int)t : c->nc[a] - 1) : 0; /* NaN -> 0 */
    return i >= c->nc[a] ? c->nc[a] - 1 : i;
}

/* Loop over the neighbours j != i of particle i (sorted, cell_of valid) within sqrt(S2) of it, in
 * cell order (deterministic). The body is the last (variadic) argument; inside it: j, and rx, ry, rz, r2 = x_i - (image of x_j) and its
 * squared length. Particle i is at (XI, YI, ZI). Periodic images are taken across periodic axes
 * (>= 3 cells each, so no pair is seen twice). */
#define SPH_FOR_EACH_NEIGHBOUR(C, P, I, XI, YI, ZI, S2, ...)                                        \
    do {                                                                                           \
        const sph_cells *nc_c_ = (C);                                                              \
        const int64_t nc_cell_ = nc_c_->cell_of[I];                                                \
        const int nc_cx_ = (int)(nc_cell_ % nc_c_->nc[0]),                                         \
                  nc_cy_ = (int)((nc_cell_ / nc_c_->nc[0]) % nc_c_->nc[1]),                        \
                  nc_cz_ = (int)(nc_cell_ / ((int64_t)nc_c_->nc[0] * nc_c_->nc[1]));               \
        const int nc_zr_ = nc_c_->dim == 3 ? 1 : 0;                                                \
        for (int nc_dz_ = -nc_zr_; nc_dz_ <= nc_zr_; nc_dz_++) {                                   \
            int nc_jz_ = nc_cz_ + nc_dz_;                                                          \
            double nc_sz_ = 0.0;                                                                   \
            if (nc_jz_ < 0 || nc_jz_ >= nc_c_->nc[2]) {                                            \
                if (!nc_c_->periodic[2])                                                           \
                    continue;                                                                      \
                nc_sz_ = (nc_jz_ < 0 ? -1.0 : 1.0) * (nc_c_->hi[2] - nc_c_->lo[2]);                \
                nc_jz_ += nc_jz_ < 0 ? nc_c_->nc[2] : -nc_c_->nc[2];                               \
            }                                                                                      \
            for (int nc_dy_ = -1; nc_dy_ <= 1; nc_dy_++) {                                         \
                int nc_jy_ = nc_cy_ + nc_dy_;                                                      \
                double nc_sy_ = 0.0;                                                               \
                if (nc_jy_ < 0 || nc_jy_ >= nc_c_->nc[1]) {                                        \
                    if (!nc_c_->periodic[1])                                                       \
                        continue;                                                                  \
                    nc_sy_ = (nc_jy_ < 0 ? -1.0 : 1.0) * (nc_c_->hi[1] - nc_c_->lo[1]);            \
                    nc_jy_ += nc_jy_ < 0 ? nc_c_->nc[1] : -nc_c_->nc[1];                           \
                }                                                                                  \
                for (int nc_dx_ = -1; nc_dx_ <= 1; nc_dx_++) {                                     \
                    int nc_jx_ = nc_cx_ + nc_dx_;                                                  \
                    double nc_sx_ = 0.0;                                                           \
                    if (nc_jx_ < 0 || nc_jx_ >= nc_c_->nc[0]) {                                    \
                        if (!nc_c_->periodic[0])                                                   \
                            continue;                                                              \
                        nc_sx_ = (nc_jx_ < 0 ? -1.0 : 1.0) * (nc_c_->hi[0] - nc_c_->lo[0]);        \
                        nc_jx_ += nc_jx_ < 0 ? nc_c_->nc[0] : -nc_c_->nc[0];                       \
                    }                                                                              \
                    const int64_t nc_nb_ = ((int64_t)nc_jz_ * nc_c_->nc[1] + nc_jy_) * nc_c_->nc[0] + nc_jx_; \
                    for (int64_t j = nc_c_->start[nc_nb_]; j < nc_c_->start[nc_nb_ + 1]; j++) {    \
                        const double rx = (XI) - ((P)->x[j] + nc_sx_), ry = (YI) - ((P)->y[j] + nc_sy_), \
                                     rz = (ZI) - ((P)->z[j] + nc_sz_);                              \
                        const double r2 = rx * rx + ry * ry + rz * rz;                             \
                        if (r2 >= (S2) || j == (I))                                                \
                            continue;                                                              \
                        __VA_ARGS__                                                                \
                    }                                                                              \
                }                                                                                  \
            }                                                                                      \
        }                                                                                          \
    } while (0)

#endif
