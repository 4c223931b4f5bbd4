/* SPH particles of the solver core as a structure of arrays, and their cell lists.
 *
 * Particles are kept sorted by cell (counting sort of the cell index, all arrays permuted, ids kept)
 * so that the neighbours of a particle are contiguous runs of memory. Cells are cubes of side >= the
 * kernel support / SPH_CELLS_PER_SUPPORT; periodic axes use the domain box exactly (positions wrapped into [lo, hi)), the
 * other axes follow the particles (bounding box recomputed at every sort). All storage is allocated
 * at setup; the cell table grows by doubling on the rare sort that needs more cells. */
#ifndef LAHAR_SPH_PARTICLES_H
#define LAHAR_SPH_PARTICLES_H
#include <stdint.h>

/* OpenMP loops over particles run in parallel only above these counts: below them a step costs
 * more in barriers than in work (measured: 25 ms per step for 250 particles on a loaded 2-core
 * machine). Heavy = neighbour or body sums per particle, light = a few flops per particle. The
 * light bound was 32768 until the water pass became symmetric: then at 24,844 particles (the
 * boulder pool of `lahar bench`) the serial light loops (integration, sort, EOS) left the second
 * thread spinning in libgomp for 15.7 % of the node's samples (perf); at 4096, 6.7 %. Their
 * reductions are max or integer sums: the same bits for any thread count. */
#define SPH_OMP_MIN_HEAVY 2048
#define SPH_OMP_MIN_LIGHT 4096
/* Heavy loops hand out particles in chunks of this many, dynamically: the cost per particle
 * varies with position (full neighbourhoods at the bottom of a column, few at its surface, body
 * sums only near walls; sorted by cell, a static split gives one thread the floor and the other
 * the surface). Each particle's result is its own gather and the reductions are integer counts,
 * so the results do not depend on which thread took which chunk (bench_sph digests unchanged). */
#define SPH_OMP_CHUNK 256

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
    /* transport velocity only (NULL until sph_particles_alloc_transport): the transport velocity
     * minus the momentum velocity, v~ - v, of the last drift (Adami et al. 2013; sph_fluid.h),
     * permuted by the sort */
    double *tvx, *tvy, *tvz;
    /* open boundaries only (NULL until sph_particles_alloc_inlet; sph_inflow.h): the index of the
     * inlet whose buffer holds the particle, -1 for a particle of the domain; permuted by the sort */
    int32_t *inlet;
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
/* Allocate the transport-velocity arrays (tvx, tvy, tvz) for cap particles, zeroed; no-op when
 * present. Returns 0 or -1 (out of memory; none allocated). */
int sph_particles_alloc_transport(sph_particles *p);
/* Allocate the inlet marks (inlet) for cap particles, set to -1; no-op when present. Returns 0
 * or -1 (out of memory). */
int sph_particles_alloc_inlet(sph_particles *p);
/* Remove the particles i with drop[i] != 0 (drop has n entries), keeping the order of the others
 * (every per-particle array moves, rates included). Returns the number removed. */
int64_t sph_particles_remove(sph_particles *p, const unsigned char *drop);
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
    double min_size;       /* kernel support / reach */
    int reach;             /* cells per kernel support: neighbours lie within +-reach cells */
    int nc[3];             /* cells per axis */
    int64_t ncell, ncell_cap;
    int64_t *start;        /* ncell + 1: particles of cell c are start[c] .. start[c+1] - 1 */
    int64_t *count;        /* ncell_cap counters for the counting sort */
    int64_t *cell_of;      /* per particle (cap) */
    int64_t *perm;         /* per particle (cap) */
    int64_t pcap;
} sph_cells;

/* Cells per kernel support (the side of a cell is >= support / SPH_CELLS_PER_SUPPORT, the stencil
 * 2 SPH_CELLS_PER_SUPPORT + 1 cells wide). 2 instead of 1: the candidates of a particle cover
 * (5/2)^D instead of 3^D supports^D, 30 % fewer distance tests in 2D and 42 % fewer in 3D. */
#ifndef SPH_CELLS_PER_SUPPORT
#define SPH_CELLS_PER_SUPPORT 2
#endif

/* Cells of side >= support / SPH_CELLS_PER_SUPPORT. Periodic axes: periodic[a] = 1 with [lo[a], hi[a]) the period, which
 * must hold >= 3 cells. Returns 0, or -1 (bad arguments, message in err, or out of memory). */
int sph_cells_init(sph_cells *c, int dim, double support, const int periodic[3], const double lo[3],
                   const double hi[3], int64_t particle_cap, char *err, int errlen);
void sph_cells_free(sph_cells *c);
/* Wrap positions on periodic axes, bin the particles and permute every particle array into cell
 * order (stable: particles of a cell keep their relative order). Returns 0, or -1 when the cell
 * table cannot grow (out of memory). */
int sph_cells_sort(sph_cells *c, sph_particles *p);
/* Blocks for pair loops that add each pair to both particles (sph_fluid.c). The cell rows along
 * the slowest axis A (y in 2D, z in 3D) are cut into runs of `reach` rows, and in 3D the rows
 * along the middle axis B (y) into runs of 2 reach; a block is one run of each (2D: one run of A,
 * all of B) and, in the sorted order, one contiguous range of particles per A row. The pairs of
 * the forward half stencil met from a block touch only the cells in its A rows and the reach rows
 * after them, and in its B rows widened by reach on both sides. So two blocks whose A runs differ
 * in parity, or whose A runs agree and B runs differ in parity, may share particles; blocks of one
 * colour (A parity, B parity) never do and can run at the same time. On a periodic axis the run
 * after the last is the first, so the count of runs is made even there (the last run takes the
 * rows left over). The blocks depend on the grid only, never on the number of threads. */
typedef struct {
    int na, nb;         /* runs along A and along B (1 in 2D); block k = (k / nb, k % nb) */
    int rows_a, rows_b; /* cell rows along A and B (1 in 2D) */
    int wa, wb;         /* rows per run along A (reach) and B (2 reach) */
} sph_blocks;
#define SPH_BLOCK_COLOURS 4
void sph_cells_blocks(const sph_cells *c, sph_blocks *b);
/* Block k's rows [*a0, *a1) along A and [*b0, *b1) along B, and its colour (0 .. 3). */
int sph_cells_block(const sph_blocks *b, int k, int *a0, int *a1, int *b0, int *b1);
/* First particle of cells (A row a, B row b, x = 0): [run(a, b0), run(a, b1)) are the block's
 * particles in row a (b1 = rows_b gives the start of row a + 1). */
static inline int64_t sph_cells_run_start(const sph_cells *c, const sph_blocks *b, int a, int brow)
{
    return c->start[((int64_t)a * b->rows_b + brow) * c->nc[0]];
}

/* Cell coordinate of a position along axis a (clamped into the grid). */
static inline int sph_cells_coord(const sph_cells *c, int a, double x)
{
    double t = (x - c->lo[a]) / c->size[a];
    int i = t >= 0.0 ? (t < (double)c->nc[a] ? (int)t : c->nc[a] - 1) : 0; /* NaN -> 0 */
    return i >= c->nc[a] ? c->nc[a] - 1 : i;
}

/* Candidates of the neighbour loop are taken in chunks of this many: distances first (no branch
 * per candidate), then the body for those within the support. */
#define SPH_NB_CHUNK 64

/* Squared distance from coordinate X of a particle along axis A to the slab of cell row K, which
 * lies D (the sign of K minus the particle's row) rows away: 0 for its own row. K is unwrapped
 * (may lie outside 0 .. nc - 1 on a periodic axis: the image slab). The slab is widened by 1e-9 of
 * a cell against rounding in the binning (sph_cells_coord), so a skipped row holds no particle
 * within the support: the neighbours and their order are those of the full stencil, bit for bit.
 * Particles clamped into an edge row lie beyond its outer face, farther still. */
#define SPH_CELL_GAP2(C, A, K, D, X)                                                                \
    ((D) == 0 ? 0.0                                                                                \
              : sph_cell_gap2_((D) > 0 ? (C)->lo[A] + (K) * (C)->size[A] - (X)                     \
                                       : (X) - ((C)->lo[A] + ((K) + 1) * (C)->size[A]),            \
                               (C)->size[A]))
static inline double sph_cell_gap2_(double gap, double size)
{
    gap -= 1e-9 * size;
    return gap > 0.0 ? gap * gap : 0.0;
}

/* Loop over the neighbours j != i of particle i (sorted, cell_of valid) within sqrt(S2) of it, in
 * cell order (deterministic). The body is the last (variadic) argument; inside it: j, and rx, ry,
 * rz, r2 = x_i - (image of x_j) and its squared length. Particle i is at (XI, YI, ZI). Periodic
 * images are taken across periodic axes (>= 3 cells each, so no pair is seen twice).
 * SPH_FOR_EACH_NEIGHBOUR_D takes the dimension DIM as a compile-time constant (2: z and rz are not
 * read, rz = 0), or 0 for the cells' own. `continue` in the body goes to the next neighbour;
 * the body must not `break`.
 * Speed: the cells of a row along x are contiguous in the sorted arrays, so a row of the stencil is
 * one run of candidates (one run per cell only where a periodic x axis wraps); each run is scanned in chunks of
 * SPH_NB_CHUNK: the squared distances of a chunk are computed and the neighbours compacted into a
 * small list without a branch per candidate (a rejected candidate, half of them in 2D and 3/4 in 3D,
 * costs no mispredicted jump), then the body runs over the list. The order of j is the cell order
 * either way. */
#define SPH_FOR_EACH_NEIGHBOUR(C, P, I, XI, YI, ZI, S2, ...)                                        \
    SPH_FOR_EACH_NEIGHBOUR_D(C, P, I, XI, YI, ZI, S2, 0, __VA_ARGS__)

#define SPH_FOR_EACH_NEIGHBOUR_D(C, P, I, XI, YI, ZI, S2, DIM, ...)                                 \
    SPH_NEIGHBOUR_CHUNKS_D(C, P, I, XI, YI, ZI, S2, DIM, {                                         \
        for (int nc_k_ = 0; nc_k_ < nb_n; nc_k_++) {                                               \
            const int64_t j = nb_j[nc_k_];                                                         \
            const double rx = nb_xi - nb_x[j], ry = nb_yi - nb_y[j],                               \
                         rz = (DIM) == 2 ? 0.0 : nb_zi - nb_z[j];                                  \
            const double r2 = rx * rx + ry * ry + rz * rz;                                         \
            (void)rx, (void)ry, (void)rz;                                                          \
            __VA_ARGS__                                                                            \
        }                                                                                          \
    })

/* The same walk a chunk at a time, for loops that want the neighbour list of a chunk as arrays
 * (e.g. to vectorise the pair sums): the body runs once per chunk with nb_n neighbours in nb_j[]
 * (k < nb_n) in cell order; x_i - x_j = (nb_xi - nb_x[j], nb_yi - nb_y[j], nb_zi - nb_z[j]) with
 * the periodic image already in nb_xi, nb_yi, nb_zi (x_i minus the shift of the run); with
 * DIM = 2 the z parts are 0 and nb_z is not to be read. */
#define SPH_NEIGHBOUR_CHUNKS_D(C, P, I, XI, YI, ZI, S2, DIM, ...)                                   \
    SPH_NEIGHBOUR_CHUNKS_(C, P, I, XI, YI, ZI, S2, DIM, 0, __VA_ARGS__)

/* The same walk over the forward half of the stencil only, for pair sums that add each pair to
 * both particles (sph_fluid.c): the rows after i's along the slowest axes (dz > 0, or dz = 0 and
 * dy > 0; all their cells along x) and, in i's own row, the particles after i in the sorted order
 * up to the cell cx + reach. Each unordered pair within the support is met exactly once, from the
 * particle that comes first (periodic axes hold >= 2 reach + 1 cells, so an offset between two
 * cells is never both forward and backward). */
#define SPH_HALF_NEIGHBOUR_CHUNKS_D(C, P, I, XI, YI, ZI, S2, DIM, ...)                              \
    SPH_NEIGHBOUR_CHUNKS_(C, P, I, XI, YI, ZI, S2, DIM, 1, __VA_ARGS__)

#define SPH_NEIGHBOUR_CHUNKS_(C, P, I, XI, YI, ZI, S2, DIM, HALF, ...)                             \
    do {                                                                                           \
        const sph_cells *nc_c_ = (C);                                                              \
        const double *const nc_px_ = (P)->x, *const nc_py_ = (P)->y, *const nc_pz_ = (P)->z;       \
        const int64_t *const nc_start_ = nc_c_->start;                                             \
        const int64_t nc_i_ = (I);                                                                 \
        const double nc_xi_ = (XI), nc_yi_ = (YI), nc_zi_ = (ZI), nc_s2_ = (S2);                   \
        const int nc_n0_ = nc_c_->nc[0], nc_n1_ = nc_c_->nc[1], nc_n2_ = nc_c_->nc[2];             \
        const int64_t nc_cell_ = nc_c_->cell_of[nc_i_];                                            \
        const int nc_cx_ = (int)(nc_cell_ % nc_n0_), nc_cy_ = (int)((nc_cell_ / nc_n0_) % nc_n1_), \
                  nc_cz_ = (int)(nc_cell_ / ((int64_t)nc_n0_ * nc_n1_));                           \
        const int nc_re_ = nc_c_->reach;                                                           \
        const int nc_zr_ = ((DIM) ? (DIM) : nc_c_->dim) == 3 ? nc_re_ : 0;                         \
        for (int nc_dz_ = (HALF) ? 0 : -nc_zr_; nc_dz_ <= nc_zr_; nc_dz_++) {                     \
            int nc_jz_ = nc_cz_ + nc_dz_;                                                          \
            /* rows of cells wholly beyond the support are skipped (SPH_CELL_GAP2) */              \
            const double nc_gz2_ = SPH_CELL_GAP2(nc_c_, 2, nc_jz_, nc_dz_, nc_zi_);                 \
            if (nc_gz2_ >= nc_s2_)                                                                 \
                continue;                                                                          \
            double nc_sz_ = 0.0;                                                                   \
            if (nc_jz_ < 0 || nc_jz_ >= nc_n2_) {                                                  \
                if (!nc_c_->periodic[2])                                                           \
                    continue;                                                                      \
                nc_sz_ = (nc_jz_ < 0 ? -1.0 : 1.0) * (nc_c_->hi[2] - nc_c_->lo[2]);                \
                nc_jz_ += nc_jz_ < 0 ? nc_n2_ : -nc_n2_;                                           \
            }                                                                                      \
            for (int nc_dy_ = (HALF) && nc_dz_ == 0 ? 0 : -nc_re_; nc_dy_ <= nc_re_; nc_dy_++) {   \
                int nc_jy_ = nc_cy_ + nc_dy_;                                                      \
                /* 3D only: in 2D a row is (nearly) never beyond the support, and the test costs */ \
                const double nc_gyz2_ = nc_zr_ > 0 ? nc_gz2_ + SPH_CELL_GAP2(nc_c_, 1, nc_jy_, nc_dy_, nc_yi_) : 0.0; \
                if (nc_gyz2_ >= nc_s2_)                                                            \
                    continue;                                                                      \
                double nc_sy_ = 0.0;                                                               \
                if (nc_jy_ < 0 || nc_jy_ >= nc_n1_) {                                              \
                    if (!nc_c_->periodic[1])                                                       \
                        continue;                                                                  \
                    nc_sy_ = (nc_jy_ < 0 ? -1.0 : 1.0) * (nc_c_->hi[1] - nc_c_->lo[1]);            \
                    nc_jy_ += nc_jy_ < 0 ? nc_n1_ : -nc_n1_;                                       \
                }                                                                                  \
                const int64_t nc_row_ = ((int64_t)nc_jz_ * nc_n1_ + nc_jy_) * nc_n0_;              \
                int64_t nc_sb_[2 * SPH_CELLS_PER_SUPPORT + 1], nc_se_[2 * SPH_CELLS_PER_SUPPORT + 1]; \
                double nc_ss_[2 * SPH_CELLS_PER_SUPPORT + 1];                                      \
                int nc_nseg_ = 0;                                                                  \
                /* along x, the cells within the support left by the row's gap */                \
                /* half stencil, own row: from i's own cell on, and there from i + 1 */           \
                const int nc_own_ = (HALF) && nc_dz_ == 0 && nc_dy_ == 0;                          \
                int nc_xa_ = nc_own_ ? nc_cx_ : nc_cx_ - nc_re_, nc_xb_ = nc_cx_ + nc_re_;         \
                if (nc_zr_ > 0) { /* 3D (in 2D the corner cells saved do not pay for the tests) */ \
                    while (nc_xa_ < nc_cx_ && nc_gyz2_ + SPH_CELL_GAP2(nc_c_, 0, nc_xa_, -1, nc_xi_) >= nc_s2_) \
                        nc_xa_++;                                                                  \
                    while (nc_xb_ > nc_cx_ && nc_gyz2_ + SPH_CELL_GAP2(nc_c_, 0, nc_xb_, 1, nc_xi_) >= nc_s2_) \
                        nc_xb_--;                                                                  \
                }                                                                                  \
                if (!nc_c_->periodic[0] || (nc_xa_ >= 0 && nc_xb_ < nc_n0_)) {                     \
                    const int nc_a_ = nc_xa_ > 0 ? nc_xa_ : 0,                                     \
                              nc_b_ = nc_xb_ < nc_n0_ ? nc_xb_ : nc_n0_ - 1;                       \
                    nc_sb_[0] = nc_own_ ? nc_i_ + 1 : nc_start_[nc_row_ + nc_a_];                  \
                    nc_se_[0] = nc_start_[nc_row_ + nc_b_ + 1];                                    \
                    nc_ss_[0] = 0.0;                                                               \
                    nc_nseg_ = 1;                                                                  \
                } else {                                                                           \
                    for (int nc_jx0_ = nc_xa_; nc_jx0_ <= nc_xb_; nc_jx0_++) {                     \
                        int nc_jx_ = nc_jx0_;                                                      \
                        double nc_sx_ = 0.0;                                                       \
                        if (nc_jx_ < 0 || nc_jx_ >= nc_n0_) {                                      \
                            nc_sx_ = (nc_jx_ < 0 ? -1.0 : 1.0) * (nc_c_->hi[0] - nc_c_->lo[0]);    \
                            nc_jx_ += nc_jx_ < 0 ? nc_n0_ : -nc_n0_;                               \
                        }                                                                          \
                        nc_sb_[nc_nseg_] = nc_own_ && nc_jx0_ == nc_cx_ ? nc_i_ + 1                \
                                                                        : nc_start_[nc_row_ + nc_jx_]; \
                        nc_se_[nc_nseg_] = nc_start_[nc_row_ + nc_jx_ + 1];                        \
                        nc_ss_[nc_nseg_++] = nc_sx_;                                               \
                    }                                                                              \
                }                                                                                  \
                for (int nc_g_ = 0; nc_g_ < nc_nseg_; nc_g_++) {                                   \
                    /* x_i minus the image shift: rx = xs - x_j (exact when the shift is 0) */     \
                    const double nb_xi = nc_xi_ - nc_ss_[nc_g_], nb_yi = nc_yi_ - nc_sy_,          \
                                 nb_zi = (DIM) == 2 ? 0.0 : nc_zi_ - nc_sz_;                       \
                    for (int64_t nc_j0_ = nc_sb_[nc_g_]; nc_j0_ < nc_se_[nc_g_]; nc_j0_ += SPH_NB_CHUNK) { \
                        const int64_t nc_j1_ = nc_se_[nc_g_] - nc_j0_ < SPH_NB_CHUNK ? nc_se_[nc_g_]     \
                                                                                    : nc_j0_ + SPH_NB_CHUNK; \
                        int64_t nc_idx_[SPH_NB_CHUNK];                                             \
                        int nc_cnt_ = 0;                                                           \
                        for (int64_t nc_j_ = nc_j0_; nc_j_ < nc_j1_; nc_j_++) {                    \
                            const double nc_dxr_ = nb_xi - nc_px_[nc_j_], nc_dyr_ = nb_yi - nc_py_[nc_j_], \
                                         nc_dzr_ = (DIM) == 2 ? 0.0 : nb_zi - nc_pz_[nc_j_];       \
                            const double nc_d2_ = nc_dxr_ * nc_dxr_ + nc_dyr_ * nc_dyr_ + nc_dzr_ * nc_dzr_; \
                            nc_idx_[nc_cnt_] = nc_j_;                                              \
                            nc_cnt_ += !(nc_d2_ >= nc_s2_) & (nc_j_ != nc_i_);                     \
                        }                                                                          \
                        {                                                                          \
                            const int nb_n = nc_cnt_;                                              \
                            const int64_t *const nb_j = nc_idx_;                                   \
                            const double *const nb_x = nc_px_, *const nb_y = nc_py_, *const nb_z = nc_pz_; \
                            (void)nb_z, (void)nb_zi;                                               \
                            __VA_ARGS__                                                            \
                        }                                                                          \
                    }                                                                              \
                }                                                                                  \
            }                                                                                      \
        }                                                                                          \
    } while (0)

#endif
