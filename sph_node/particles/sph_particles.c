/* SPH particle storage and cell lists (sph_particles.h). */
#include "sph_particles.h"
#include "soa_alloc.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SPH_NDOUBLE 17
/* Every double array of a particle set, so that allocation, release and sorting treat all alike. */
static void particle_doubles(sph_particles *p, double **a[SPH_NDOUBLE])
{
    double **list[SPH_NDOUBLE] = {&p->x,  &p->y,  &p->z,  &p->vx,  &p->vy,  &p->vz,  &p->rho, &p->p,   &p->m,
                                  &p->ax, &p->ay, &p->az, &p->drho, &p->vhx, &p->vhy, &p->vhz, &p->rhoh};
    memcpy(a, list, sizeof list);
}

int sph_particles_init(sph_particles *p, int64_t cap)
{
    memset(p, 0, sizeof *p);
    if (cap < 1)
        cap = 1;
    double **a[SPH_NDOUBLE];
    particle_doubles(p, a);
    int ok = 1;
    for (int k = 0; k < SPH_NDOUBLE; k++)
        ok &= (*a[k] = lahar_soa_calloc((size_t)cap, sizeof(double))) != NULL;
    ok &= (p->scratch_d = lahar_soa_calloc((size_t)cap, sizeof(double))) != NULL;
    ok &= (p->id = lahar_soa_calloc((size_t)cap, sizeof *p->id)) != NULL;
    ok &= (p->scratch_i = lahar_soa_calloc((size_t)cap, sizeof *p->scratch_i)) != NULL;
    ok &= (p->phase = lahar_soa_calloc((size_t)cap, sizeof *p->phase)) != NULL;
    ok &= (p->scratch_p = lahar_soa_calloc((size_t)cap, sizeof *p->scratch_p)) != NULL;
    if (!ok) {
        sph_particles_free(p);
        return -1;
    }
    p->cap = cap;
    return 0;
}

int sph_particles_alloc_stress(sph_particles *p)
{
    if (p->sig[0])
        return 0;
    int ok = 1;
    for (int k = 0; k < SPH_NSTRESS; k++) {
        ok &= (p->sig[k] = lahar_soa_calloc((size_t)p->cap, sizeof(double))) != NULL;
        ok &= (p->sigh[k] = lahar_soa_calloc((size_t)p->cap, sizeof(double))) != NULL;
    }
    if (!ok) {
        for (int k = 0; k < SPH_NSTRESS; k++) {
            lahar_soa_free(p->sig[k]), lahar_soa_free(p->sigh[k]);
            p->sig[k] = p->sigh[k] = NULL;
        }
        return -1;
    }
    return 0;
}

int sph_particles_alloc_transport(sph_particles *p)
{
    if (p->tvx)
        return 0;
    p->tvx = lahar_soa_calloc((size_t)p->cap, sizeof(double));
    p->tvy = lahar_soa_calloc((size_t)p->cap, sizeof(double));
    p->tvz = lahar_soa_calloc((size_t)p->cap, sizeof(double));
    if (!p->tvx || !p->tvy || !p->tvz) {
        lahar_soa_free(p->tvx), lahar_soa_free(p->tvy), lahar_soa_free(p->tvz);
        p->tvx = p->tvy = p->tvz = NULL;
        return -1;
    }
    return 0;
}

int sph_particles_alloc_inlet(sph_particles *p)
{
    if (p->inlet)
        return 0;
    if (!(p->inlet = lahar_soa_calloc((size_t)p->cap, sizeof *p->inlet)))
        return -1;
    for (int64_t i = 0; i < p->cap; i++)
        p->inlet[i] = -1;
    return 0;
}

int64_t sph_particles_remove(sph_particles *p, const unsigned char *drop)
{
    const int64_t n = p->n;
    double **a[SPH_NDOUBLE + 2 * SPH_NSTRESS + 3];
    particle_doubles(p, a);
    int na = SPH_NDOUBLE;
    if (p->sig[0])
        for (int k = 0; k < SPH_NSTRESS; k++)
            a[na++] = &p->sig[k], a[na++] = &p->sigh[k];
    if (p->tvx)
        a[na++] = &p->tvx, a[na++] = &p->tvy, a[na++] = &p->tvz;
    int64_t j = 0;
    for (int64_t i = 0; i < n; i++) {
        if (drop[i])
            continue;
        if (j != i) {
            for (int k = 0; k < na; k++)
                (*a[k])[j] = (*a[k])[i];
            p->id[j] = p->id[i];
            p->phase[j] = p->phase[i];
            if (p->inlet)
                p->inlet[j] = p->inlet[i];
        }
        j++;
    }
    p->n = j;
    return n - j;
}

void sph_particles_free(sph_particles *p)
{
    lahar_soa_free(p->inlet);
    lahar_soa_free(p->tvx), lahar_soa_free(p->tvy), lahar_soa_free(p->tvz);
    for (int k = 0; k < SPH_NSTRESS; k++)
        lahar_soa_free(p->sig[k]), lahar_soa_free(p->sigh[k]);
    double **a[SPH_NDOUBLE];
    particle_doubles(p, a);
    for (int k = 0; k < SPH_NDOUBLE; k++)
        lahar_soa_free(*a[k]);
    lahar_soa_free(p->scratch_d);
    lahar_soa_free(p->id);
    lahar_soa_free(p->scratch_i);
    lahar_soa_free(p->phase);
    lahar_soa_free(p->scratch_p);
    memset(p, 0, sizeof *p);
}

int64_t sph_particles_add(sph_particles *p, const double x[3], const double v[3], double m, double rho,
                          int32_t phase)
{
    if (p->n >= p->cap)
        return -1;
    int64_t i = p->n++;
    p->x[i] = x[0], p->y[i] = x[1], p->z[i] = x[2];
    p->vx[i] = v[0], p->vy[i] = v[1], p->vz[i] = v[2];
    p->vhx[i] = v[0], p->vhy[i] = v[1], p->vhz[i] = v[2];
    p->m[i] = m;
    p->rho[i] = p->rhoh[i] = rho;
    p->p[i] = 0.0;
    p->ax[i] = p->ay[i] = p->az[i] = p->drho[i] = 0.0;
    p->phase[i] = phase;
    p->id[i] = i;
    return i;
}

int64_t sph_particles_add_box(sph_particles *p, int dim, double dx, double rho, const double lo[3], const double hi[3],
                              const double v[3])
{
    int64_t n[3];
    for (int a = 0; a < 3; a++) {
        n[a] = (a == 2 && dim == 2) ? 1 : (int64_t)floor((hi[a] - lo[a]) / dx + 1e-9);
        if (n[a] < 0)
            n[a] = 0;
    }
    if (n[0] * n[1] * n[2] > p->cap - p->n)
        return -1;
    double m = rho * pow(dx, dim);
    double v2[3] = {v[0], v[1], dim == 2 ? 0.0 : v[2]};
    for (int64_t i = 0; i < n[0]; i++)
        for (int64_t j = 0; j < n[1]; j++)
            for (int64_t k = 0; k < n[2]; k++) {
                double x[3] = {lo[0] + ((double)i + 0.5) * dx, lo[1] + ((double)j + 0.5) * dx,
                               dim == 2 ? 0.0 : lo[2] + ((double)k + 0.5) * dx};
                sph_particles_add(p, x, v2, m, rho, 0);
            }
    return n[0] * n[1] * n[2];
}

int sph_cells_init(sph_cells *c, int dim, double support, const int periodic[3], const double lo[3],
                   const double hi[3], int64_t particle_cap, char *err, int errlen)
{
    memset(c, 0, sizeof *c);
    c->dim = dim;
    c->reach = SPH_CELLS_PER_SUPPORT;
    c->min_size = support / c->reach;
    if (!(support > 0.0)) {
        snprintf(err, (size_t)errlen, "kernel support must be > 0");
        return -1;
    }
    for (int a = 0; a < 3; a++) {
        c->periodic[a] = periodic && periodic[a] && !(a == 2 && dim == 2);
        c->lo[a] = lo ? lo[a] : 0.0;
        c->hi[a] = hi ? hi[a] : 0.0;
        c->size[a] = c->min_size;
        c->nc[a] = 1;
        if (c->periodic[a]) {
            double len = c->hi[a] - c->lo[a];
            int nc = (int)floor(len / support);
            if (nc < 3) { /* then >= 3 reach cells: no pair is seen twice */
                snprintf(err, (size_t)errlen,
                         "periodic axis %c: period %g m holds %d cells of the kernel support %g m; it needs >= 3",
                         "xyz"[a], len, nc, support);
                return -1;
            }
            nc = (int)floor(len / c->min_size);
            c->nc[a] = nc;
            c->size[a] = len / nc;
        }
    }
    c->pcap = particle_cap < 1 ? 1 : particle_cap;
    c->ncell_cap = 1024;
    c->start = calloc((size_t)c->ncell_cap + 1, sizeof *c->start);
    c->count = calloc((size_t)c->ncell_cap, sizeof *c->count);
    c->cell_of = lahar_soa_calloc((size_t)c->pcap, sizeof *c->cell_of);
    c->perm = lahar_soa_calloc((size_t)c->pcap, sizeof *c->perm);
    if (!c->start || !c->count || !c->cell_of || !c->perm) {
        sph_cells_free(c);
        snprintf(err, (size_t)errlen, "out of memory");
        return -1;
    }
    return 0;
}

void sph_cells_free(sph_cells *c)
{
    free(c->start);
    free(c->count);
    lahar_soa_free(c->cell_of);
    lahar_soa_free(c->perm);
    memset(c, 0, sizeof *c);
}

/* The arrays a sort permutes: the state and the half-step state. The rates (ax, ay, az, drho) and
 * the pressure p are not: they belong to the positions before the sort and every caller evaluates
 * them again after it (sph_fluid_rates), so moving them would be wasted memory traffic. */
#define SPH_NSORTED 12
static void sorted_doubles(sph_particles *p, double **a[SPH_NSORTED])
{
    double **list[SPH_NSORTED] = {&p->x,  &p->y,  &p->z,  &p->vx,  &p->vy,  &p->vz,
                                  &p->rho, &p->m, &p->vhx, &p->vhy, &p->vhz, &p->rhoh};
    memcpy(a, list, sizeof list);
}

/* The grid over the particles: periodic axes keep their period and take the particles that left it
 * back in; the others span the particles' extent in cells of at least min_size. */
static void cells_fit_grid(sph_cells *c, sph_particles *p, int par)
{
    const int64_t n = p->n;
    double *pos[3] = {p->x, p->y, p->z};
    for (int a = 0; a < 3; a++) {
        if (a == 2 && c->dim == 2) {
            c->nc[2] = 1;
            continue;
        }
        double *x = pos[a];
        if (c->periodic[a]) {
            double lo = c->lo[a], len = c->hi[a] - c->lo[a];
#pragma omp parallel for schedule(static) if (par)
            for (int64_t i = 0; i < n; i++) {
                if (x[i] < lo || x[i] >= lo + len) {
                    x[i] -= floor((x[i] - lo) / len) * len;
                    if (x[i] >= lo + len) /* rounding of a value just below lo */
                        x[i] = lo;
                }
            }
            continue;
        }
        /* min and max are exact: the same bounds for any number of threads; NaN is skipped */
        double mn = INFINITY, mx = -INFINITY;
#pragma omp parallel for schedule(static) reduction(min : mn) reduction(max : mx) if (par)
        for (int64_t i = 0; i < n; i++) {
            mn = x[i] < mn ? x[i] : mn;
            mx = x[i] > mx ? x[i] : mx;
        }
        if (!(mn <= mx)) /* no particles (or all NaN): one cell */
            mn = mx = 0.0;
        c->lo[a] = mn;
        c->hi[a] = mx;
        c->size[a] = c->min_size;
        double nc = floor((mx - mn) / c->size[a]) + 1.0;
        c->nc[a] = nc > 1e6 ? 1000000 : (int)nc;
        c->size[a] = fmax(c->min_size, (mx - mn) / c->nc[a] * (1.0 + 1e-12));
    }
    /* a particle flying far away must not blow up the table: coarsen the non-periodic axes */
    int64_t limit = 8 * c->pcap + 4096;
    for (;;) {
        int64_t ncell = (int64_t)c->nc[0] * c->nc[1] * c->nc[2];
        if (ncell <= limit)
            break;
        for (int a = 0; a < c->dim; a++)
            if (!c->periodic[a] && c->nc[a] > 1) {
                c->nc[a] = (c->nc[a] + 1) / 2;
                c->size[a] = fmax(c->min_size, (c->hi[a] - c->lo[a]) / c->nc[a] * (1.0 + 1e-12));
            }
    }
}

/* Room for ncell cells in the start and count tables (doubling: rare, never in a steady run). */
static int cells_reserve(sph_cells *c, int64_t ncell)
{
    if (ncell <= c->ncell_cap)
        return 0;
    int64_t cap = c->ncell_cap;
    while (cap < ncell)
        cap *= 2;
    int64_t *s = realloc(c->start, (size_t)(cap + 1) * sizeof *s);
    if (!s)
        return -1;
    c->start = s;
    int64_t *cnt = realloc(c->count, (size_t)cap * sizeof *cnt);
    if (!cnt)
        return -1;
    c->count = cnt;
    c->ncell_cap = cap;
    return 0;
}

/* Each particle's cell, then a counting sort: the cells' start offsets and the permutation that
 * orders the particles by cell (serial: a few operations per particle; stable, so the order within
 * a cell and hence every sum over neighbours is the same for any number of threads). */
static void cells_count_sort(sph_cells *c, const sph_particles *p, int par)
{
    const int64_t n = p->n, ncell = c->ncell;
    const int d3 = c->dim == 3;
#pragma omp parallel for schedule(static) if (par)
    for (int64_t i = 0; i < n; i++) {
        int ix = sph_cells_coord(c, 0, p->x[i]), iy = sph_cells_coord(c, 1, p->y[i]);
        int iz = d3 ? sph_cells_coord(c, 2, p->z[i]) : 0;
        c->cell_of[i] = ((int64_t)iz * c->nc[1] + iy) * c->nc[0] + ix;
    }
    memset(c->count, 0, (size_t)ncell * sizeof *c->count);
    for (int64_t i = 0; i < n; i++)
        c->count[c->cell_of[i]]++;
    c->start[0] = 0;
    for (int64_t k = 0; k < ncell; k++) {
        c->start[k + 1] = c->start[k] + c->count[k];
        c->count[k] = c->start[k]; /* now the insertion cursor */
    }
    for (int64_t i = 0; i < n; i++)
        c->perm[c->count[c->cell_of[i]]++] = i;
}

/* Every particle array into the order perm (gathers, one parallel region): each array is gathered
 * into its scratch array, which then takes its place. */
static void particles_permute(sph_particles *p, const int64_t *perm, int par)
{
    const int64_t n = p->n;
    double **a[SPH_NSORTED + 2 * SPH_NSTRESS + 3];
    sorted_doubles(p, a);
    int na = SPH_NSORTED;
    if (p->sig[0]) /* soil stress and its half-step value */
        for (int k = 0; k < SPH_NSTRESS; k++)
            a[na++] = &p->sig[k], a[na++] = &p->sigh[k];
    if (p->tvx) /* transport velocity offset */
        a[na++] = &p->tvx, a[na++] = &p->tvy, a[na++] = &p->tvz;
#pragma omp parallel if (par)
    {
        for (int k = 0; k < na; k++) {
            const double *src = *a[k];
            double *out = p->scratch_d;
#pragma omp for schedule(static)
            for (int64_t i = 0; i < n; i++)
                out[i] = src[perm[i]];
            /* implicit barrier: every thread has finished reading src before the swap */
#pragma omp single
            {
                p->scratch_d = *a[k];
                *a[k] = out;
            }
        }
#pragma omp for schedule(static) nowait
        for (int64_t i = 0; i < n; i++)
            p->scratch_i[i] = p->id[perm[i]];
#pragma omp for schedule(static)
        for (int64_t i = 0; i < n; i++)
            p->scratch_p[i] = p->phase[perm[i]];
    }
    int64_t *ti = p->id;
    p->id = p->scratch_i;
    p->scratch_i = ti;
    int32_t *tp = p->phase;
    p->phase = p->scratch_p;
    p->scratch_p = tp;
    if (p->inlet) { /* open boundaries only: the scratch now holds the old phases, free to reuse */
#pragma omp parallel for schedule(static) if (par)
        for (int64_t i = 0; i < n; i++)
            p->scratch_p[i] = p->inlet[perm[i]];
        tp = p->inlet;
        p->inlet = p->scratch_p;
        p->scratch_p = tp;
    }
}

int sph_cells_sort(sph_cells *c, sph_particles *p)
{
    const int64_t n = p->n;
    if (n > c->pcap)
        return -1;
    const int par = n >= SPH_OMP_MIN_LIGHT;
    cells_fit_grid(c, p, par);
    const int64_t ncell = (int64_t)c->nc[0] * c->nc[1] * c->nc[2];
    if (cells_reserve(c, ncell) != 0)
        return -1;
    c->ncell = ncell;
    cells_count_sort(c, p, par);
    particles_permute(p, c->perm, par);
    /* cell_of in the new order */
    int64_t *cell_of = c->cell_of;
#pragma omp parallel for schedule(static) if (par)
    for (int64_t k = 0; k < ncell; k++)
        for (int64_t i = c->start[k]; i < c->start[k + 1]; i++)
            cell_of[i] = k;
    return 0;
}

/* runs of w rows out of `rows`: at least 1, even on a periodic axis */
static int block_runs(int rows, int w, int periodic)
{
    int n = rows / w;
    if (n < 1)
        n = 1;
    if (periodic && n > 1 && n % 2 == 1)
        n--;
    return n;
}

void sph_cells_blocks(const sph_cells *c, sph_blocks *b)
{
    const int d3 = c->dim == 3, A = d3 ? 2 : 1;
    b->rows_a = c->nc[A];
    b->rows_b = d3 ? c->nc[1] : 1;
    b->wa = c->reach;
    b->wb = 2 * c->reach;
    b->na = block_runs(b->rows_a, b->wa, c->periodic[A]);
    b->nb = d3 ? block_runs(b->rows_b, b->wb, c->periodic[1]) : 1;
}

int sph_cells_block(const sph_blocks *b, int k, int *a0, int *a1, int *b0, int *b1)
{
    const int ka = k / b->nb, kb = k % b->nb;
    *a0 = ka * b->wa;
    *a1 = ka == b->na - 1 ? b->rows_a : (ka + 1) * b->wa;
    *b0 = kb * b->wb;
    *b1 = kb == b->nb - 1 ? b->rows_b : (kb + 1) * b->wb;
    return (ka % 2) * 2 + kb % 2;
}
