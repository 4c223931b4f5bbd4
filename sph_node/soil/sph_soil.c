/* SPH soil: Drucker-Prager stress, its rates and the soil momentum (sph_soil.h). */
#include "sph_soil.h"
#include "soa_alloc.h"
#include "sph_soil_model.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* component index of the symmetric tensor (xx, xy, xz, yy, yz, zz) */
static const int SYM[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};

int sph_soil_init(sph_soil *s, const sph_soil_material *m, int dim, const kernel *k, double dx, sph_particles *p)
{
    memset(s, 0, sizeof *s);
    s->mat = *m;
    s->dim = dim;
    s->model = m->model ? m->model : sph_soil_model_find("drucker_prager");
    s->model->init(s);
    s->w_dx = kernel_w(k, dx);
    s->seep = m->kh > 0.0 ? m->rho_water * m->g_ref / m->kh : 0.0;
    s->cap = p->cap;
    if (sph_particles_alloc_stress(p) != 0)
        return -1;
    int ok = 1;
    for (int a = 0; a < SPH_NSTRESS; a++) {
        ok &= (s->dsig[a] = lahar_soa_calloc((size_t)s->cap, sizeof(double))) != NULL;
        ok &= (s->rart[a] = lahar_soa_calloc((size_t)s->cap, sizeof(double))) != NULL;
        ok &= (s->sig_rho2[a] = lahar_soa_calloc((size_t)s->cap, sizeof(double))) != NULL;
    }
    ok &= (s->tensile = lahar_soa_calloc((size_t)s->cap, 1)) != NULL;
    /* soil neighbours of pass 1 for pass 2: room for 1.5 x the lattice's count plus 16 (a soil
     * compressed beyond that walks the cells again, particle by particle) */
    const double sr = k->support / dx;
    const double nominal = dim == 3 ? 4.0 / 3.0 * M_PI * sr * sr * sr : M_PI * sr * sr;
    s->nb_stride = (int)(1.5 * nominal) + 16;
    ok &= (s->nb_n = lahar_soa_calloc((size_t)s->cap, sizeof *s->nb_n)) != NULL;
    ok &= (s->nb_j = lahar_soa_calloc((size_t)s->cap * (size_t)s->nb_stride, sizeof *s->nb_j)) != NULL;
    if (!ok) {
        sph_soil_free(s);
        return -1;
    }
    return 0;
}

void sph_soil_free(sph_soil *s)
{
    for (int a = 0; a < SPH_NSTRESS; a++)
        lahar_soa_free(s->dsig[a]), lahar_soa_free(s->rart[a]), lahar_soa_free(s->sig_rho2[a]);
    lahar_soa_free(s->tensile);
    lahar_soa_free(s->nb_n), lahar_soa_free(s->nb_j);
    for (int a = 0; a < 9; a++)
        lahar_soa_free(s->grad[a]);
    memset(s, 0, sizeof *s);
}

void sph_soil_return(const sph_soil *s, double sig[SPH_NSTRESS]) { s->model->admissible(s, sig); }

/* Artificial stress of one particle (sph_soil.h): eigen-decomposition of the symmetric stress by
 * cyclic Jacobi rotations (a fixed, small number of sweeps: deterministic), R'_aa from the tensile
 * principal stresses, rotated back. out is R / rho^2 * (-eps) applied: the term added to the pair sum. */
static void soil_artificial_stress(const double sig[SPH_NSTRESS], double rho, double out[SPH_NSTRESS])
{
    double a[3][3], v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            a[i][j] = sig[SYM[i][j]];
    for (int sweep = 0; sweep < 8; sweep++) {
        double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        double diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if (off <= 1e-30 * diag || off == 0.0)
            break;
        for (int p = 0; p < 2; p++)
            for (int q = p + 1; q < 3; q++) {
                if (a[p][q] == 0.0)
                    continue;
                double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                double t = (theta >= 0.0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (int k = 0; k < 3; k++) { /* a = J^T a J, columns then rows */
                    double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; k++) {
                    double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 3; k++) {
                    double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
    }
    double r[3];
    for (int k = 0; k < 3; k++)
        r[k] = a[k][k] > 0.0 ? -SPH_SOIL_AS_EPS * a[k][k] / (rho * rho) : 0.0;
    for (int i = 0; i < 3; i++)
        for (int j = i; j < 3; j++)
            out[SYM[i][j]] = v[i][0] * r[0] * v[j][0] + v[i][1] * r[1] * v[j][1] + v[i][2] * r[2] * v[j][2];
}

/* The stress rate of soil particle i from its velocity gradient L into s->dsig: the strain rate
 * and spin, then the constitutive model's objective rate (sph_soil_model.h). */
static void soil_stress_rate(sph_soil *s, const sph_particles *p, int64_t i, const double L[3][3])
{
    double sig[3][3], eps[3][3], spin[3][3], out[SPH_NSTRESS];
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) {
            sig[a][b] = p->sig[SYM[a][b]][i];
            eps[a][b] = 0.5 * (L[a][b] + L[b][a]);
            spin[a][b] = 0.5 * (L[a][b] - L[b][a]);
        }
    s->model->stress_rate(s, (const double(*)[3])sig, (const double(*)[3])eps, (const double(*)[3])spin, out);
    for (int c = 0; c < SPH_NSTRESS; c++)
        s->dsig[c][i] = out[c];
}

int sph_soil_keep_gradient(sph_soil *s)
{
    for (int a = 0; a < 9; a++)
        if (!s->grad[a] && !(s->grad[a] = lahar_soa_calloc((size_t)s->cap, sizeof(double))))
            return -1;
    return 0;
}

void sph_soil_wall_gradient(sph_soil *s, const sph_particles *p, int64_t i, const double Lw[9])
{
    double L[3][3];
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++)
            L[a][b] = s->grad[a * 3 + b][i] + Lw[a * 3 + b];
    soil_stress_rate(s, p, i, (const double(*)[3])L);
}

static void soil_stress_particle(sph_soil *s, sph_particles *p, const sph_cells *c, const kernel *k,
                                 const double *vol, int record, int64_t i)
{
    const double inv_h = k->inv_h, dnorm = k->dnorm, s2 = k->support * k->support;
    const kernel_kind kind = k->kind;
    const double xi = p->x[i], yi = p->y[i], zi = p->z[i];
    const double vxi = p->vx[i], vyi = p->vy[i], vzi = p->vz[i];
    double L[3][3] = {{0.0}}; /* L[a][b] = d v_a / d x_b */
    int32_t *const list = record ? s->nb_j + (size_t)i * (size_t)s->nb_stride : NULL;
    const int stride = s->nb_stride;
    int nlist = 0;
    SPH_FOR_EACH_NEIGHBOUR(c, p, i, xi, yi, zi, s2, {
        if (p->phase[j] != SPH_SOIL_PHASE)
            continue;
        if (record) {
            if (nlist < stride)
                list[nlist] = (int32_t)j;
            nlist++;
        }
        double r = sqrt(r2);
        double fij = r > 0.0 ? dnorm * kernel_dshape(kind, r * inv_h) / r : 0.0;
        double w = vol[j] * fij;
        double dv[3] = {p->vx[j] - vxi, p->vy[j] - vyi, p->vz[j] - vzi};
        double xr[3] = {rx, ry, rz};
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++)
                L[a][b] += w * dv[a] * xr[b];
    });
    if (s->grad[0]) /* kept for the wall's share (sph_soil_wall_gradient) */
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++)
                s->grad[a * 3 + b][i] = L[a][b];
    soil_stress_rate(s, p, i, (const double(*)[3])L);
    double own[SPH_NSTRESS];
    for (int a = 0; a < SPH_NSTRESS; a++)
        own[a] = p->sig[a][i];
    double rart[SPH_NSTRESS];
    soil_artificial_stress(own, p->rho[i], rart);
    unsigned char tensile = 0;
    const double irho2 = 1.0 / (p->rho[i] * p->rho[i]);
    for (int a = 0; a < SPH_NSTRESS; a++) {
        s->sig_rho2[a][i] = own[a] * irho2;
        s->rart[a][i] = rart[a];
        tensile |= rart[a] != 0.0;
    }
    s->tensile[i] = tensile;
    if (record)
        s->nb_n[i] = nlist <= stride ? nlist : -1;
    p->p[i] = -(own[0] + own[3] + own[5]) / 3.0;
}

/* Pass 2 may reuse pass 1's soil neighbours when it needs no others (no seepage: water
 * neighbours are skipped) and x_i - x_j needs no periodic image (the walk's rx = (x_i - shift) -
 * x_j would not be reproduced bit for bit): the same pairs in the same order, so the same bits. */
static int soil_list_usable(const sph_soil *s, const sph_cells *c)
{
    return !(s->seep > 0.0) && !c->periodic[0] && !c->periodic[1] && !c->periodic[2] && s->cap < INT32_MAX;
}

void sph_soil_stress_rates(sph_soil *s, sph_particles *p, const sph_cells *c, const kernel *k, const double *vol)
{
    const int64_t n = p->n;
    const int record = soil_list_usable(s, c);
#pragma omp parallel for schedule(dynamic, SPH_OMP_CHUNK) if (n >= SPH_OMP_MIN_HEAVY)
    for (int64_t i = 0; i < n; i++)
        if (p->phase[i] == SPH_SOIL_PHASE)
            soil_stress_particle(s, p, c, k, vol, record, i);
}

/* The soil-soil pair (i, j) of pass 2 (sph_soil.h, momentum): continuity, stress divergence,
 * artificial stress and viscosity, added to acc (drho, ax, ay, az). */
static inline __attribute__((always_inline)) void soil_momentum_pair(const sph_soil *s, const sph_particles *p,
                                                                     const kernel *k, const double si[SPH_NSTRESS],
                                                                     const double ri[SPH_NSTRESS], int tensile_i,
                                                                     double rhoi, double vxi, double vyi,
                                                                     double vzi, int64_t j, double rx, double ry,
                                                                     double rz, double r2, double acc[4])
{
    const double h = k->h, inv_h = k->inv_h, dnorm = k->dnorm;
    const kernel_kind kind = k->kind;
    const double eta2 = 0.01 * h * h, cs = s->cs, inv_wdx = 1.0 / s->w_dx;
    double r = sqrt(r2);
    double q = r * inv_h;
    double fij = r > 0.0 ? dnorm * kernel_dshape(kind, q) / r : 0.0;
    double vx = vxi - p->vx[j], vy = vyi - p->vy[j], vz = vzi - p->vz[j];
    double rhoj = p->rho[j], mj = p->m[j];
    double vdotr = vx * rx + vy * ry + vz * rz;
    acc[0] += rhoi * mj / rhoj * vdotr * fij; /* continuity without the delta term */
    double pi_ij = 0.0;
    if (vdotr < 0.0) { /* Monaghan 1992 */
        double mu = h * vdotr / (r2 + eta2);
        pi_ij = (-s->mat.av_alpha * cs * mu + s->mat.av_beta * mu * mu) / (0.5 * (rhoi + rhoj));
    }
    double t[SPH_NSTRESS];
    if (tensile_i | s->tensile[j]) { /* the artificial stress; pow is ~20 % of a soil step */
        double fn = pow(k->norm * kernel_shape(kind, q) * inv_wdx, SPH_SOIL_AS_N);
        for (int a = 0; a < SPH_NSTRESS; a++)
            t[a] = si[a] + s->sig_rho2[a][j] + (ri[a] + s->rart[a][j]) * fn;
    } else { /* R_i = R_j = 0 (no tension at either): the same sum without the zero term */
        for (int a = 0; a < SPH_NSTRESS; a++)
            t[a] = si[a] + s->sig_rho2[a][j];
    }
    t[0] -= pi_ij, t[3] -= pi_ij, t[5] -= pi_ij;
    double mf = mj * fij; /* grad_i W_ij = F_ij x_ij */
    acc[1] += mf * (t[0] * rx + t[1] * ry + t[2] * rz);
    acc[2] += mf * (t[1] * rx + t[3] * ry + t[4] * rz);
    acc[3] += mf * (t[2] * rx + t[4] * ry + t[5] * rz);
}

/* Returns the soil neighbours summed over; *nwater the water neighbours (seepage only). */
static int64_t soil_momentum_particle(const sph_soil *s, sph_particles *p, const sph_cells *c, const kernel *k,
                                      int use_list, int64_t i, int64_t *nwater)
{
    const double *g = s->mat.gravity;
    const double inv_h = k->inv_h, dnorm = k->dnorm, s2 = k->support * k->support;
    const kernel_kind kind = k->kind;
    const double xi = p->x[i], yi = p->y[i], zi = p->z[i];
    const double vxi = p->vx[i], vyi = p->vy[i], vzi = p->vz[i];
    const double rhoi = p->rho[i];
    double si[SPH_NSTRESS], ri[SPH_NSTRESS];
    for (int a = 0; a < SPH_NSTRESS; a++) {
        si[a] = s->sig_rho2[a][i];
        ri[a] = s->rart[a][i];
    }
    const int tensile_i = s->tensile[i];
    double acc[4] = {0.0, 0.0, 0.0, 0.0}; /* drho, ax, ay, az */
    const double seep = s->seep, wnorm = k->norm;
    int64_t nsoil = 0, nw = 0; /* work counters */
    const int nlist = use_list ? s->nb_n[i] : -1;
    if (nlist >= 0) { /* pass 1's soil neighbours, in its order (soil_list_usable) */
        const int32_t *const list = s->nb_j + (size_t)i * (size_t)s->nb_stride;
        const int dim3 = k->dim == 3;
        for (int m = 0; m < nlist; m++) {
            const int64_t j = list[m];
            const double rx = xi - p->x[j], ry = yi - p->y[j], rz = dim3 ? zi - p->z[j] : 0.0;
            const double r2 = rx * rx + ry * ry + rz * rz;
            soil_momentum_pair(s, p, k, si, ri, tensile_i, rhoi, vxi, vyi, vzi, j, rx, ry, rz, r2, acc);
        }
        nsoil = nlist;
    } else {
        SPH_FOR_EACH_NEIGHBOUR(c, p, i, xi, yi, zi, s2, {
            if (p->phase[j] != SPH_SOIL_PHASE) {
                if (seep > 0.0) { /* water neighbour: seepage and pore pressure (Trujillo-Vela et al. 2020, eq. 9, 10) */
                    nw++;
                    double r = sqrt(r2), q = r * inv_h;
                    double fij = r > 0.0 ? dnorm * kernel_dshape(kind, q) / r : 0.0;
                    double c1 = p->m[j] / (p->rho[j] * rhoi);
                    double sw = c1 * seep * wnorm * kernel_shape(kind, q), pw = -c1 * p->p[j] * fij;
                    acc[1] += sw * (p->vx[j] - vxi) + pw * rx;
                    acc[2] += sw * (p->vy[j] - vyi) + pw * ry;
                    acc[3] += sw * (p->vz[j] - vzi) + pw * rz;
                }
                continue;
            }
            nsoil++;
            soil_momentum_pair(s, p, k, si, ri, tensile_i, rhoi, vxi, vyi, vzi, j, rx, ry, rz, r2, acc);
        });
    }
    p->drho[i] = acc[0];
    const double cd = s->mat.damping;
    p->ax[i] = acc[1] + g[0] - cd * vxi;
    p->ay[i] = acc[2] + g[1] - cd * vyi;
    p->az[i] = acc[3] + g[2] - cd * vzi;
    *nwater = nw;
    return nsoil;
}

int64_t sph_soil_momentum(const sph_soil *s, sph_particles *p, const sph_cells *c, const kernel *k,
                          int64_t *water_neighbours)
{
    const int64_t n = p->n;
    const int use_list = soil_list_usable(s, c);
    int64_t nsoil = 0, nwater = 0; /* integer sums: exact in any order */
#pragma omp parallel for schedule(dynamic, SPH_OMP_CHUNK) reduction(+ : nsoil, nwater) if (n >= SPH_OMP_MIN_HEAVY)
    for (int64_t i = 0; i < n; i++)
        if (p->phase[i] == SPH_SOIL_PHASE) {
            int64_t nw = 0;
            nsoil += soil_momentum_particle(s, p, c, k, use_list, i, &nw);
            nwater += nw;
        }
    *water_neighbours = nwater;
    return nsoil;
}

int64_t sph_soil_water_seepage(const sph_soil *s, sph_particles *p, const sph_cells *c, const kernel *k)
{
    const int64_t n = p->n;
    const double seep = s->seep, inv_h = k->inv_h, dnorm = k->dnorm, wnorm = k->norm, s2 = k->support * k->support;
    const kernel_kind kind = k->kind;
    if (!(seep > 0.0))
        return 0;
    int64_t nsoil = 0; /* work counter: soil neighbours of the water particles */
#pragma omp parallel for schedule(dynamic, SPH_OMP_CHUNK) reduction(+ : nsoil) if (n >= SPH_OMP_MIN_HEAVY)
    for (int64_t i = 0; i < n; i++) {
        if (p->phase[i] == SPH_SOIL_PHASE)
            continue;
        const double vxi = p->vx[i], vyi = p->vy[i], vzi = p->vz[i], rhoi = p->rho[i], pi_ = p->p[i];
        double ax = 0.0, ay = 0.0, az = 0.0;
        SPH_FOR_EACH_NEIGHBOUR(c, p, i, p->x[i], p->y[i], p->z[i], s2, {
            if (p->phase[j] != SPH_SOIL_PHASE)
                continue;
            nsoil++;
            double r = sqrt(r2), q = r * inv_h;
            double fij = r > 0.0 ? dnorm * kernel_dshape(kind, q) / r : 0.0; /* grad_f W_fs = F x_fs */
            double c1 = p->m[j] / (rhoi * p->rho[j]);
            double sw = c1 * seep * wnorm * kernel_shape(kind, q), pw = c1 * pi_ * fij;
            ax -= sw * (vxi - p->vx[j]) + pw * rx;
            ay -= sw * (vyi - p->vy[j]) + pw * ry;
            az -= sw * (vzi - p->vz[j]) + pw * rz;
        });
        p->ax[i] += ax;
        p->ay[i] += ay;
        p->az[i] += az;
    }
    return nsoil;
}

void sph_soil_kick_begin(const sph_soil *s, sph_particles *p, int64_t i, double hdt)
{
    double sig[SPH_NSTRESS];
    for (int a = 0; a < SPH_NSTRESS; a++) {
        p->sigh[a][i] = p->sig[a][i] + hdt * s->dsig[a][i];
        sig[a] = p->sigh[a][i];
    }
    sph_soil_return(s, sig);
    for (int a = 0; a < SPH_NSTRESS; a++)
        p->sigh[a][i] = sig[a];
    for (int a = 0; a < SPH_NSTRESS; a++)
        sig[a] = p->sigh[a][i] + hdt * s->dsig[a][i];
    sph_soil_return(s, sig);
    for (int a = 0; a < SPH_NSTRESS; a++)
        p->sig[a][i] = sig[a];
}

void sph_soil_kick_end(const sph_soil *s, sph_particles *p, int64_t i, double hdt)
{
    double sig[SPH_NSTRESS];
    for (int a = 0; a < SPH_NSTRESS; a++)
        sig[a] = p->sigh[a][i] + hdt * s->dsig[a][i];
    sph_soil_return(s, sig);
    for (int a = 0; a < SPH_NSTRESS; a++)
        p->sig[a][i] = sig[a];
}
