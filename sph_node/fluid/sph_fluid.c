/* WCSPH solver core (sph_fluid.h). */
#include "sph_fluid.h"
#include "soa_alloc.h"
#include "sph_eos.h"
#include "sph_riemann.h"
#include "sph_pair_terms.h"
#include "sph_fluid_units.h"
#include "case.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void sph_params_default(sph_params *prm)
{
    memset(prm, 0, sizeof *prm);
    lahar_sph_options_default(&prm->opt);
}

int sph_fluid_init(sph_fluid *f, const sph_params *prm, int64_t cap, char *err, int errlen)
{
    memset(f, 0, sizeof *f);
    f->prm = *prm;
    const sph_params *p = &f->prm;
    const lahar_sph_options *o = &p->opt;
    if (!(p->dx > 0.0) || !(p->rho0 > 0.0) || !(o->c0 > 0.0) || o->mu < 0.0 || (p->dim != 2 && p->dim != 3)) {
        snprintf(err, (size_t)errlen, "SPH parameters: need dim 2 or 3, dx > 0, rho0 > 0, c0 > 0, mu >= 0");
        return -1;
    }
    /* the options come from the loader or sph_params_default, never zero */
    if (!(o->h_over_dx > 0.0) || !(o->cfl > 0.0) || !(o->cfl_force > 0.0) || !(o->cfl_visc > 0.0) ||
        (o->eos == LAHAR_SPH_EOS_TAIT && !(o->gamma > 0.0)) || (o->sps && !(o->sps_cs > 0.0))) {
        snprintf(err, (size_t)errlen, "SPH parameters: h_over_dx, cfl, cfl_force, cfl_visc (and gamma, sps_cs when "
                 "used) must be > 0; start from sph_params_default");
        return -1;
    }
    if (kernel_init(&f->k, o->kernel, p->dim, o->h_over_dx * p->dx) != 0) {
        snprintf(err, (size_t)errlen, "unknown kernel '%s' (cubic, quintic, wendland2)", o->kernel);
        return -1;
    }
    if (sph_particles_init(&f->p, cap) != 0) {
        snprintf(err, (size_t)errlen, "out of memory for %lld particles", (long long)cap);
        return -1;
    }
    if (sph_cells_init(&f->cells, p->dim, f->k.support, o->periodic, o->lo, o->hi, f->p.cap, err, errlen) != 0) {
        sph_particles_free(&f->p);
        return -1;
    }
    f->prho2 = lahar_soa_calloc((size_t)f->p.cap, sizeof(double));
    f->vol = lahar_soa_calloc((size_t)f->p.cap, sizeof(double));
    if (!f->prho2 || !f->vol) {
        lahar_soa_free(f->prho2);
        lahar_soa_free(f->vol);
        sph_cells_free(&f->cells);
        sph_particles_free(&f->p);
        snprintf(err, (size_t)errlen, "out of memory for %lld particles", (long long)cap);
        return -1;
    }
    if (o->sps) {
        /* nu_t and the six stress components in one block, only when SPS is on */
        double *buf = lahar_soa_calloc((size_t)f->p.cap * 7, sizeof(double));
        if (!buf) {
            lahar_soa_free(f->prho2);
            lahar_soa_free(f->vol);
            sph_cells_free(&f->cells);
            sph_particles_free(&f->p);
            snprintf(err, (size_t)errlen, "out of memory for the SPS stress of %lld particles", (long long)cap);
            return -1;
        }
        f->sps_nut = buf;
        for (int a = 0; a < 6; a++)
            f->sps_tau[a] = buf + (size_t)f->p.cap * (size_t)(a + 1);
    }
    if (o->transport_velocity) { /* v~ - v per particle, and the background-pressure acceleration */
        double *buf = lahar_soa_calloc((size_t)f->p.cap * 3, sizeof(double));
        if (!buf || sph_particles_alloc_transport(&f->p) != 0) {
            lahar_soa_free(buf);
            lahar_soa_free(f->sps_nut);
            lahar_soa_free(f->prho2);
            lahar_soa_free(f->vol);
            sph_cells_free(&f->cells);
            sph_particles_free(&f->p);
            snprintf(err, (size_t)errlen, "out of memory for the transport velocity of %lld particles", (long long)cap);
            return -1;
        }
        f->tv_bx = buf;
        f->tv_by = buf + f->p.cap;
        f->tv_bz = buf + 2 * f->p.cap;
    }
    if (p->soil) { /* stress arrays only when the scene has soil */
        if (sph_soil_init(&f->soil, &p->soil_mat, p->dim, &f->k, p->dx, &f->p) != 0) {
            lahar_soa_free(f->sps_nut);
            lahar_soa_free(f->tv_bx);
            lahar_soa_free(f->prho2);
            lahar_soa_free(f->vol);
            sph_cells_free(&f->cells);
            sph_particles_free(&f->p);
            snprintf(err, (size_t)errlen, "out of memory for the soil stress of %lld particles", (long long)cap);
            return -1;
        }
        f->has_soil = 1;
    }
    return 0;
}

int sph_fluid_attach_bodies(sph_fluid *f, int nbody, const lahar_body *bodies)
{
    double m_min = INFINITY;
    for (int64_t i = 0; i < f->p.n; i++)
        m_min = fmin(m_min, f->p.m[i]);
    if (!(m_min < INFINITY))
        m_min = f->prm.rho0 * pow(f->prm.dx, f->prm.dim);
    if (f->has_bodies)
        sph_coupling_free(&f->cpl);
    f->has_bodies = 0;
    if (sph_coupling_init(&f->cpl, f->prm.dim, nbody, bodies, &f->k, f->prm.dx, m_min, f->prm.opt.mu,
                          f->prm.opt.wall_viscous, f->p.cap) != 0)
        return -1;
    sph_coupling_set_periodic(&f->cpl, f->prm.opt.periodic, f->prm.opt.lo, f->prm.opt.hi); /* bodies act across them */
    if (f->has_soil && sph_coupling_enable_soil(&f->cpl, f->prm.soil_mat.mu_phi) != 0) { /* Trujillo-Vela et al. 2020, section 4.2 */
        sph_coupling_free(&f->cpl);
        return -1;
    }
    /* the ghosts' hydrostatic extrapolation uses the body force along the non-periodic axes only,
     * as the delta-SPH hydrostatic part does (a periodic driving force makes a flow, not a
     * pressure gradient) */
    double bh[3];
    for (int a = 0; a < 3; a++)
        bh[a] = f->prm.opt.periodic[a] ? 0.0 : f->prm.body_force[a];
    f->cpl.cells = &f->cells;
    /* K_n with the acoustic step (sph_coupling.kn_dt): the CFL step at rest, cfl h / c (the
     * larger of c0 and the soil's sound speed) */
    if (f->prm.opt.penalty_stiffness == LAHAR_SPH_PENALTY_ACOUSTIC)
        f->cpl.kn_dt = f->prm.opt.cfl * f->k.h / fmax(f->prm.opt.c0, f->has_soil ? f->soil.cs : 0.0);
    f->cpl.riemann = f->prm.opt.scheme == LAHAR_SPH_SCHEME_RIEMANN;
    f->cpl.riemann_c0 = f->prm.opt.c0;
    f->cpl.riemann_eta = f->prm.opt.riemann_limiter;
    if (sph_coupling_set_wall_pressure(&f->cpl, f->prm.opt.wall_pressure, bh, f->prm.dx) != 0) {
        sph_coupling_free(&f->cpl);
        return -1;
    }
    if (f->has_soil) { /* the soil's ghost stress extrapolates with its gravity (the case's) */
        double gs[3];
        for (int a = 0; a < 3; a++)
            gs[a] = f->prm.opt.periodic[a] ? 0.0 : f->prm.soil_mat.gravity[a];
        if (sph_coupling_set_soil_wall(&f->cpl, f->prm.opt.soil_wall_stress, gs, f->prm.dx) != 0 ||
            (f->prm.opt.soil_wall_stress == LAHAR_SPH_WALL_PRESSURE_GHOST && sph_soil_keep_gradient(&f->soil) != 0)) {
            sph_coupling_free(&f->cpl);
            return -1;
        }
    }
    f->has_bodies = 1;
    f->primed = 0;
    return 0;
}

void sph_fluid_free(sph_fluid *f)
{
    if (f->has_bodies)
        sph_coupling_free(&f->cpl);
    lahar_soa_free(f->sps_nut);
    lahar_soa_free(f->tv_bx);
    lahar_soa_free(f->prho2);
    lahar_soa_free(f->vol);
    if (f->has_soil)
        sph_soil_free(&f->soil);
    sph_cells_free(&f->cells);
    sph_particles_free(&f->p);
    memset(f, 0, sizeof *f);
}

double sph_fluid_pressure(const sph_params *prm, double rho)
{
    return sph_eos_get(prm->opt.eos)->pressure(rho, prm->rho0, prm->opt.c0, prm->opt.gamma);
}

double sph_fluid_density_of_pressure(const sph_params *prm, double p)
{
    return sph_eos_get(prm->opt.eos)->density(p, prm->rho0, prm->opt.c0, prm->opt.gamma);
}

static inline int prm_tvf(const sph_fluid *f) { return f->prm.opt.transport_velocity != 0; }

/* The pairs (i, j) of water particle i with the water particles j after it in the forward half
 * stencil (SPH_HALF_NEIGHBOUR_CHUNKS_D), each evaluated once and added to both particles: the
 * density rates to drho[] and the pair force F_ij = m_i m_j (dv_i/dt)_j to fx[], fy[], fz[]
 * (+F_ij to i, -F_ij to j: the momentum terms are antisymmetric in i and j, sph_fluid.h).
 * `kind`, `sps`, `soil` and `dim` are compile-time constants at each call site of the switch in
 * fluid_pass, so the kernel evaluation inlines without a branch per pair and 2D reads no z
 * components. Per pair: one square root and one division (1/(r^2 + eta^2)), a second only for
 * approaching pairs with artificial viscosity; p_j/rho_j^2 and V_j = m_j/rho_j come precomputed
 * (f->prho2, f->vol), W'/r = dnorm/h f'(q)/q (kernel_dshape_over_q). With soil, pairs with a soil
 * particle are skipped (sph_soil.h). i's own sums are added to its entries after its pairs (they
 * may already hold the terms of pairs met from particles before it). Returns the pairs evaluated. */
static inline __attribute__((always_inline)) int64_t fluid_pairs(const sph_fluid *f, const kernel_kind kind,
                                                                 const int sps, const int soil, const int dim,
                                                                 int64_t i, double *restrict drho,
                                                                 double *restrict fx, double *restrict fy,
                                                                 double *restrict fz)
{
    const sph_particles *p = &f->p;
    /* transport velocity (Adami et al. 2013, sph_fluid.h): background-pressure force into
     * tv_bx.., the extra stress A = rho v (v~ - v) into the pair force */
    const int tvf = prm_tvf(f);
    double *const bxa = f->tv_bx, *const bya = f->tv_by, *const bza = f->tv_bz;
    const double *const tvxa = p->tvx, *const tvya = p->tvy, *const tvza = p->tvz;
    const double pb = f->prm.opt.background_pressure;
    double bxi = 0.0, byi = 0.0, bzi = 0.0;
    const sph_cells *c = &f->cells;
    const sph_params *prm = &f->prm;
    const double *const vxa = p->vx, *const vya = p->vy, *const vza = p->vz, *const rhoa = p->rho,
                 *const ma = p->m, *const pra = f->prho2, *const vola = f->vol;
    const double h = f->k.h, inv_h = f->k.inv_h, fnorm = f->k.dnorm * f->k.inv_h,
                 s2 = f->k.support * f->k.support;
    const double eta2 = 0.01 * h * h;
    const double xi = p->x[i], yi = p->y[i], zi = dim == 2 ? 0.0 : p->z[i];
    const double vxi = p->vx[i], vyi = p->vy[i], vzi = dim == 2 ? 0.0 : p->vz[i];
    const double rhoi = p->rho[i], pri = pra[i], mi = ma[i], voli = vola[i];
    /* Morris: m_i m_j (mu_i + mu_j)/(rho_i rho_j) = 2 mu V_i V_j */
    const double visci = 2.0 * prm->opt.mu * voli;
    const double c0 = prm->opt.c0, alpha = prm->opt.alpha, ddelta = 2.0 * prm->opt.delta * h * c0;
    /* Monaghan: Pi_ij = -alpha c0 h v_ij.x_ij/(r^2 + eta^2) / rho_ij, rho_ij = (rho_i + rho_j)/2 */
    const double av = 2.0 * alpha * c0 * h;
    /* hydrostatic density difference per unit x_ij, rho0 b / c0^2, from the body force along the
     * non-periodic axes (Fourtakas et al. 2019): delta-SPH diffuses only the deviation from it */
    const double hx = prm->opt.periodic[0] ? 0.0 : prm->rho0 * prm->body_force[0] / (c0 * c0),
                 hy = prm->opt.periodic[1] ? 0.0 : prm->rho0 * prm->body_force[1] / (c0 * c0),
                 hz = prm->opt.periodic[2] || dim == 2 ? 0.0 : prm->rho0 * prm->body_force[2] / (c0 * c0);
    /* Riemann scheme (sph_riemann.h): p_i itself (with p_b) and the limiter */
    const int riem = prm->opt.scheme == LAHAR_SPH_SCHEME_RIEMANN;
    const double pi_full = pri * rhoi * rhoi, reta = prm->opt.riemann_limiter;
    /* SPS stress of i over rho_i^2 (Canelas et al. 2015, eq. 10); unused when sps is 0 */
    double ti[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    double *const *tau = f->sps_tau;
    if (sps)
        for (int a = 0; a < 6; a++)
            ti[a] = tau[a][i] / (rhoi * rhoi);
    double drhoi = 0.0, fxi = 0.0, fyi = 0.0, fzi = 0.0;
    int64_t npair = 0;
    const int32_t *const ph = p->phase;
    SPH_HALF_NEIGHBOUR_CHUNKS_D(c, p, i, xi, yi, zi, s2, dim, {
        for (int k = 0; k < nb_n; k++) {
            const int64_t j = nb_j[k];
            if (soil && ph[j] != 0) /* soil neighbours: sph_soil.h (fluid-soil: Trujillo-Vela et al. 2020 section 2.3) */
                continue;
            npair++;
            const double rx = nb_xi - nb_x[j], ry = nb_yi - nb_y[j], rz = dim == 2 ? 0.0 : nb_zi - nb_z[j];
            const double r2 = rx * rx + ry * ry + rz * rz;
            const double r = sqrt(r2);
            const double fij = fnorm * kernel_dshape_over_q(kind, r * inv_h); /* W'/r */
            const double vx = vxi - vxa[j], vy = vyi - vya[j], vz = dim == 2 ? 0.0 : vzi - vza[j];
            const double rhoj = rhoa[j], volj = vola[j], mj = ma[j];
            const double vdotr = vx * rx + vy * ry + vz * rz;
            const double ieta = 1.0 / (r2 + eta2), rsoft = r2 * ieta;
            /* continuity (Trujillo-Vela et al. 2020, eq. 1) and delta-SPH (sign: diffuses, see sph_fluid.h); x_ji = -x_ij,
             * v_ji.x_ji = v_ij.x_ij, and the diffusion term changes sign */
            double gp;
            if (riem) {
                /* Riemann scheme (sph_fluid.h, sph_riemann.h; Zhang, Hu & Adams 2017): along e_ij = -x_ij/r,
                 * U_L - U_R = -v_ij.x_ij/r. Continuity 2 rho_i V_j (v_i - v*).grad_i W_ij =
                 * rho_i V_j F_ij (v_ij.x_ij + (p_i - p_j - rho0 b.x_ij) r/(rhobar c0)); momentum
                 * -m_i m_j 2 P* / (rho_i rho_j) F_ij x_ij */
                const double pj = pra[j] * rhoj * rhoj, rhobar = 0.5 * (rhoi + rhoj);
                const double du = r > 0.0 ? -vdotr / r : 0.0;
                const double dpd = (pi_full - pj - c0 * c0 * (hx * rx + hy * ry + hz * rz)) * r / (rhobar * c0);
                drhoi += volj * fij * rhoi * (vdotr + dpd);
                drho[j] += voli * fij * rhoj * (vdotr - dpd);
                const double ps = sph_riemann_pstar(pi_full, pj, rhobar, c0, du, reta);
                gp = -mi * mj * 2.0 * ps / (rhoi * rhoj) * fij;
            } else {
                const double dev = sph_delta_diffusion(ddelta, rhoi, rhoj, hx * rx + hy * ry + hz * rz, rsoft);
                drhoi += volj * fij * (rhoi * vdotr + dev);
                drho[j] += voli * fij * (rhoj * vdotr - dev);
                /* pressure, symmetric (Trujillo-Vela et al. 2020, eq. 2), with Monaghan's Pi_ij > 0 when approaching
                 * (av = 0 without artificial viscosity): -m_i m_j (...) F_ij x_ij */
                const double pav = sph_monaghan_viscosity(av, vdotr, ieta, rhoi, rhoj);
                gp = -mi * mj * (pri + pra[j] - pav) * fij;
            }
            /* laminar viscosity, Morris 1997: 2 mu V_i V_j F_ij r^2/(r^2 + eta^2) v_ij. With the
             * transport velocity, Adami et al. 2013's shear term mu (V_i^2 + V_j^2) F_ij v_ij (equal
             * for equal volumes) has no eta: F_ij is finite at r = 0 for every kernel here, and the
             * regularisation weakens a pair at r by 0.01 (h/r)^2 (4 % at r = dx for h = 2 dx), which
             * alone slowed the Taylor-Green decay by 1 % (docs/bench/validation.md) */
            const double gv = sph_morris_viscosity(visci, volj, fij, tvf ? 1.0 : rsoft);
            double Fx = gp * rx + gv * vx, Fy = gp * ry + gv * vy, Fz = dim == 3 ? gp * rz + gv * vz : 0.0;
            if (sps) { /* Canelas et al. 2015, eq. 10, third term: m_i m_j (tau_i/rho_i^2 + tau_j/rho_j^2) . grad_i W_ij */
                const double tj[6] = {tau[0][j], tau[1][j], tau[2][j], tau[3][j], tau[4][j], tau[5][j]};
                sph_sps_pair(ti, tj, 1.0 / (rhoj * rhoj), mi * mj * fij, rx, ry, rz, dim, &Fx, &Fy, &Fz);
            }
            if (tvf) {
                /* 1/rho div A, symmetric: m_i m_j (A_i/rho_i^2 + A_j/rho_j^2) . grad_i W_ij, with
                 * (A/rho^2 . grad W)_a = v_a ((v~ - v) . grad W) / rho */
                const double mf = mi * mj * fij;
                const double si = (tvxa[i] * rx + tvya[i] * ry + (dim == 3 ? tvza[i] * rz : 0.0)) / rhoi;
                const double sj = (tvxa[j] * rx + tvya[j] * ry + (dim == 3 ? tvza[j] * rz : 0.0)) / rhoj;
                sph_transport_pair(mf, si, sj, vxi, vyi, vzi, vxa[j], vya[j], dim == 3 ? vza[j] : 0.0, dim, &Fx, &Fy, &Fz);
                /* background pressure: -m_i m_j p_b (1/rho_i^2 + 1/rho_j^2) grad_i W_ij */
                const double gb = sph_background_pair(mi, mj, pb, rhoi, rhoj, fij);
                bxi += gb * rx, byi += gb * ry;
                bxa[j] -= gb * rx, bya[j] -= gb * ry;
                if (dim == 3)
                    bzi += gb * rz, bza[j] -= gb * rz;
            }
            fxi += Fx, fyi += Fy;
            fx[j] -= Fx, fy[j] -= Fy;
            if (dim == 3)
                fzi += Fz, fz[j] -= Fz;
        }
    });
    if (tvf) {
        bxa[i] += bxi;
        bya[i] += byi;
        if (dim == 3)
            bza[i] += bzi;
    }
    drho[i] += drhoi;
    fx[i] += fxi;
    fy[i] += fyi;
    if (dim == 3)
        fz[i] += fzi;
    return npair;
}

/* The pairs of the water particles of block k (sph_cells_blocks), particle by particle in the
 * sorted order; soil particles are left to sph_soil_momentum. Returns the pairs evaluated. */
static inline __attribute__((always_inline)) int64_t fluid_block(const sph_fluid *f, const kernel_kind kind,
                                                                 const int sps, const int soil, const int dim,
                                                                 const sph_blocks *blk, int k, double *restrict drho,
                                                                 double *restrict fx, double *restrict fy,
                                                                 double *restrict fz)
{
    const sph_cells *c = &f->cells;
    const int32_t *const phase = f->p.phase;
    int a0, a1, b0, b1;
    sph_cells_block(blk, k, &a0, &a1, &b0, &b1);
    int64_t pairs = 0;
    for (int a = a0; a < a1; a++) {
        const int64_t i1 = sph_cells_run_start(c, blk, a, b1);
        for (int64_t i = sph_cells_run_start(c, blk, a, b0); i < i1; i++)
            if (!soil || phase[i] == 0)
                pairs += fluid_pairs(f, kind, sps, soil, dim, i, drho, fx, fy, fz);
    }
    return pairs;
}

/* The water's particle-particle sums (sph_fluid.h) in symmetric form: each pair once
 * (fluid_pairs), its terms added to both particles. Threads must not add to one particle at the
 * same time, and the sums must come out bitwise the same for any number of threads: the particles
 * are split into blocks of cell rows (sph_cells_blocks) in four colours; the blocks of one colour
 * share no particle, so they run in parallel, one colour after the other. Each block runs its
 * particles in order on one thread, so every particle receives its terms in an order fixed by the
 * blocks alone. Then F/m + g (soil particles too: sph_soil_momentum overwrites theirs). */
static void fluid_pass(sph_fluid *f)
{
    sph_particles *p = &f->p;
    const sph_cells *c = &f->cells;
    const int64_t n = p->n;
    const kernel_kind kind = f->k.kind;
    const int sps = f->prm.opt.sps != 0, d3 = f->prm.dim == 3;
    const int soil = f->has_soil;
    const int tvf = prm_tvf(f);
    double *const drho = p->drho, *const fx = p->ax, *const fy = p->ay, *const fz = p->az;
    sph_blocks blk;
    sph_cells_blocks(c, &blk);
    int64_t pairs = 0;
#pragma omp parallel if (n >= SPH_OMP_MIN_HEAVY)
    {
#pragma omp for schedule(static)
        for (int64_t i = 0; i < n; i++)
            drho[i] = fx[i] = fy[i] = fz[i] = 0.0;
        if (tvf) {
#pragma omp for schedule(static)
            for (int64_t i = 0; i < n; i++)
                f->tv_bx[i] = f->tv_by[i] = f->tv_bz[i] = 0.0;
        }
        for (int colour = 0; colour < SPH_BLOCK_COLOURS; colour++) {
            /* the blocks of this colour: every second run along A and B from (pa, pb) */
            const int pa = colour >> 1, pb = colour & 1;
            const int nka = (blk.na - pa + 1) / 2, nkb = (blk.nb - pb + 1) / 2;
            /* blocks differ in cost (a water column's top, a tank's empty part): handed out one by
             * one; which thread runs a block does not change the order within it */
#pragma omp for schedule(dynamic, 1) reduction(+ : pairs)
            for (int t = 0; t < nka * nkb; t++) {
                const int k = (pa + 2 * (t / nkb)) * blk.nb + pb + 2 * (t % nkb);
                /* kind, sps, soil and dim constant per call site: the pair loop inlines without their branches */
#define FLUID_BLOCK_DIM(K, S, L)                                                                   \
    (d3 ? fluid_block(f, K, S, L, 3, &blk, k, drho, fx, fy, fz) : fluid_block(f, K, S, L, 2, &blk, k, drho, fx, fy, fz))
                switch ((kind * 2 + sps) * 2 + soil) {
                case KERNEL_QUINTIC * 4: pairs += FLUID_BLOCK_DIM(KERNEL_QUINTIC, 0, 0); break;
                case KERNEL_QUINTIC * 4 + 1: pairs += FLUID_BLOCK_DIM(KERNEL_QUINTIC, 0, 1); break;
                case KERNEL_QUINTIC * 4 + 2: pairs += FLUID_BLOCK_DIM(KERNEL_QUINTIC, 1, 0); break;
                case KERNEL_QUINTIC * 4 + 3: pairs += FLUID_BLOCK_DIM(KERNEL_QUINTIC, 1, 1); break;
                case KERNEL_WENDLAND2 * 4: pairs += FLUID_BLOCK_DIM(KERNEL_WENDLAND2, 0, 0); break;
                case KERNEL_WENDLAND2 * 4 + 1: pairs += FLUID_BLOCK_DIM(KERNEL_WENDLAND2, 0, 1); break;
                case KERNEL_WENDLAND2 * 4 + 2: pairs += FLUID_BLOCK_DIM(KERNEL_WENDLAND2, 1, 0); break;
                case KERNEL_WENDLAND2 * 4 + 3: pairs += FLUID_BLOCK_DIM(KERNEL_WENDLAND2, 1, 1); break;
                case KERNEL_CUBIC * 4 + 1: pairs += FLUID_BLOCK_DIM(KERNEL_CUBIC, 0, 1); break;
                case KERNEL_CUBIC * 4 + 2: pairs += FLUID_BLOCK_DIM(KERNEL_CUBIC, 1, 0); break;
                case KERNEL_CUBIC * 4 + 3: pairs += FLUID_BLOCK_DIM(KERNEL_CUBIC, 1, 1); break;
                default: pairs += FLUID_BLOCK_DIM(KERNEL_CUBIC, 0, 0); break;
                }
#undef FLUID_BLOCK_DIM
            }
        }
        /* forces to accelerations, plus the body force */
        const double gx = f->prm.body_force[0], gy = f->prm.body_force[1], gz = f->prm.body_force[2];
        const double *const m = p->m;
#pragma omp for schedule(static)
        for (int64_t i = 0; i < n; i++) {
            const double im = 1.0 / m[i];
            fx[i] = fx[i] * im + gx;
            fy[i] = fy[i] * im + gy;
            fz[i] = fz[i] * im + gz;
        }
        if (tvf) {
#pragma omp for schedule(static)
            for (int64_t i = 0; i < n; i++) {
                const double im = 1.0 / m[i];
                f->tv_bx[i] *= im;
                f->tv_by[i] *= im;
                f->tv_bz[i] *= im;
            }
        }
    }
    f->work_passes++;
    f->work_neighbours_fluid += 2 * pairs; /* (i, j) and (j, i); integer sum: exact in any order */
}

/* EOS, SPS and the particle-particle sums: everything of the rates that does not need the bodies. */
static void fluid_rates_particles(sph_fluid *f)
{
    sph_particles *p = &f->p;
    const int64_t n = p->n;
    const sph_params prm = f->prm;
    if (prm.opt.transport_velocity)
        sph_fluid_summation_density(f);
    double *const prho2 = f->prho2, *const vol = f->vol;
    /* background pressure in the momentum equation (p = p_EOS + p_b), unless the transport
     * velocity takes it (sph_fluid.h); p.p keeps the EOS pressure */
    const double pbm = prm.opt.transport_velocity ? 0.0 : prm.opt.background_pressure;
#pragma omp parallel for schedule(static) if (n >= SPH_OMP_MIN_LIGHT)
    for (int64_t i = 0; i < n; i++) {
        const double rho = p->rho[i], pr = sph_fluid_pressure(&prm, rho);
        p->p[i] = pr;
        prho2[i] = (pbm > 0.0 ? pr + pbm : pr) / (rho * rho);
        vol[i] = p->m[i] / rho;
    }
    if (prm.opt.sps)
        sph_fluid_sps_pass(f);
    if (f->has_soil) /* stress rates, artificial stress and p = -tr(sigma)/3 of the soil */
        sph_soil_stress_rates(&f->soil, p, &f->cells, &f->k, f->vol);
    fluid_pass(f);
    if (prm.opt.transport_velocity) /* the density is the summation of the positions, not integrated */
        memset(p->drho, 0, (size_t)n * sizeof *p->drho);
    if (f->has_soil) {
        int64_t soil_water = 0;
        f->work_neighbours_soil += sph_soil_momentum(&f->soil, p, &f->cells, &f->k, &soil_water);
        /* Trujillo-Vela et al. 2020, eq. 8, when k_h > 0 */
        f->work_neighbours_fluid_soil += soil_water + sph_soil_water_seepage(&f->soil, p, &f->cells, &f->k);
    }
}

/* The soil stress in the leapfrog (sph_soil.h): begin = the half kick and the prediction, else the
 * final half kick. */
static void fluid_soil_kick(sph_fluid *f, double hdt, int begin)
{
    sph_particles *p = &f->p;
    const int64_t n = p->n;
#pragma omp parallel for schedule(static) if (n >= SPH_OMP_MIN_LIGHT)
    for (int64_t i = 0; i < n; i++) {
        if (p->phase[i] != SPH_SOIL_PHASE)
            continue;
        if (begin)
            sph_soil_kick_begin(&f->soil, p, i, hdt);
        else
            sph_soil_kick_end(&f->soil, p, i, hdt);
    }
}

/* The coupling with the bodies at `states`, and vmax/amax: the rest of the rates. */
static int64_t fluid_rates_bodies(sph_fluid *f, const lahar_body_state *states, double dt)
{
    sph_particles *p = &f->p;
    const int64_t n = p->n;
    int64_t cross = 0;
    if (f->has_bodies) {
        sph_coupling_mark(&f->cpl, &f->cells, n, states);
        cross = sph_coupling_apply(&f->cpl, p, states, dt);
        if (cross < 0)
            return -1;
        if (f->has_soil && f->cpl.soil_lw_on) { /* the soil ghosts' share of the velocity gradient */
#pragma omp parallel for schedule(static) if (n >= SPH_OMP_MIN_LIGHT)
            for (int64_t i = 0; i < n; i++)
                if (f->cpl.soil_lw_on[i] && p->phase[i] == SPH_SOIL_PHASE)
                    sph_soil_wall_gradient(&f->soil, p, i, f->cpl.soil_lw[i]);
        }
    }
    double vmax2 = 0.0, amax2 = 0.0;
#pragma omp parallel for schedule(static) reduction(max : vmax2, amax2) if (n >= SPH_OMP_MIN_LIGHT)
    for (int64_t i = 0; i < n; i++) {
        double v2 = p->vx[i] * p->vx[i] + p->vy[i] * p->vy[i] + p->vz[i] * p->vz[i];
        double a2 = p->ax[i] * p->ax[i] + p->ay[i] * p->ay[i] + p->az[i] * p->az[i];
        vmax2 = v2 > vmax2 ? v2 : vmax2;
        amax2 = a2 > amax2 ? a2 : amax2;
    }
    f->vmax = sqrt(vmax2);
    f->amax = sqrt(amax2);
    if (f->prm.opt.sps) { /* the eddy viscosity joins the viscous step limit */
        double nutmax = 0.0;
#pragma omp parallel for schedule(static) reduction(max : nutmax) if (n >= SPH_OMP_MIN_LIGHT)
        for (int64_t i = 0; i < n; i++)
            nutmax = f->sps_nut[i] > nutmax ? f->sps_nut[i] : nutmax;
        f->nut_max = nutmax;
    }
    f->primed = 1;
    return cross;
}

int64_t sph_fluid_rates(sph_fluid *f, const lahar_body_state *states, double dt)
{
    fluid_rates_particles(f);
    return fluid_rates_bodies(f, states, dt);
}

int sph_fluid_step_begin(sph_fluid *f, double dt)
{
    sph_particles *p = &f->p;
    if (!f->primed) {
        if (sph_cells_sort(&f->cells, p) != 0 || sph_fluid_rates(f, NULL, dt) < 0)
            return -1;
    }
    const int64_t n = p->n;
    const double hdt = 0.5 * dt;
    const int d3 = f->prm.dim == 3;
    /* restrict: the arrays are distinct, so the loop vectorises */
    double *restrict x = p->x, *restrict y = p->y, *restrict z = p->z;
    double *restrict vx = p->vx, *restrict vy = p->vy, *restrict vz = p->vz, *restrict rho = p->rho;
    double *restrict vhx = p->vhx, *restrict vhy = p->vhy, *restrict vhz = p->vhz, *restrict rhoh = p->rhoh;
    const double *restrict ax = p->ax, *restrict ay = p->ay, *restrict az = p->az, *restrict drho = p->drho;
    /* kick (half), drift, predict; one loop per dimension so that neither tests d3 per particle
     * (both vectorise); 2D: z, vz and vhz are not touched (they stay 0) */
    if (f->prm.opt.transport_velocity) {
        /* Adami et al. 2013: the particles move with the transport velocity
         * v~ = v(t + dt/2) + dt/2 b(t), b the background-pressure acceleration of the last
         * evaluation; tv = v~ - v is kept for the extra stress A of the next evaluation */
        double *restrict tvx = p->tvx, *restrict tvy = p->tvy, *restrict tvz = p->tvz;
        const double *restrict bx = f->tv_bx, *restrict by = f->tv_by, *restrict bz = f->tv_bz;
#pragma omp parallel for schedule(static) if (n >= SPH_OMP_MIN_LIGHT)
        for (int64_t i = 0; i < n; i++) {
            const double hx = vx[i] + hdt * ax[i], hy = vy[i] + hdt * ay[i], hz = d3 ? vz[i] + hdt * az[i] : 0.0;
            const double rh = rho[i] + hdt * drho[i];
            tvx[i] = hdt * bx[i], tvy[i] = hdt * by[i], tvz[i] = d3 ? hdt * bz[i] : 0.0;
            vhx[i] = hx, vhy[i] = hy, rhoh[i] = rh;
            x[i] += dt * (hx + tvx[i]), y[i] += dt * (hy + tvy[i]);
            vx[i] = hx + hdt * ax[i], vy[i] = hy + hdt * ay[i];
            if (d3) {
                vhz[i] = hz;
                z[i] += dt * (hz + tvz[i]);
                vz[i] = hz + hdt * az[i];
            }
            rho[i] = rh + hdt * drho[i];
        }
    } else if (d3) {
#pragma omp parallel for schedule(static) if (n >= SPH_OMP_MIN_LIGHT)
        for (int64_t i = 0; i < n; i++) {
            const double hx = vx[i] + hdt * ax[i], hy = vy[i] + hdt * ay[i], hz = vz[i] + hdt * az[i];
            const double rh = rho[i] + hdt * drho[i];
            vhx[i] = hx, vhy[i] = hy, vhz[i] = hz, rhoh[i] = rh;
            x[i] += dt * hx, y[i] += dt * hy, z[i] += dt * hz;
            vx[i] = hx + hdt * ax[i], vy[i] = hy + hdt * ay[i], vz[i] = hz + hdt * az[i];
            rho[i] = rh + hdt * drho[i];
        }
    } else {
#pragma omp parallel for schedule(static) if (n >= SPH_OMP_MIN_LIGHT)
        for (int64_t i = 0; i < n; i++) {
            const double hx = vx[i] + hdt * ax[i], hy = vy[i] + hdt * ay[i];
            const double rh = rho[i] + hdt * drho[i];
            vhx[i] = hx, vhy[i] = hy, rhoh[i] = rh;
            x[i] += dt * hx, y[i] += dt * hy;
            vx[i] = hx + hdt * ax[i], vy[i] = hy + hdt * ay[i];
            rho[i] = rh + hdt * drho[i];
        }
    }
    if (f->has_soil)
        fluid_soil_kick(f, hdt, 1);
    if (sph_cells_sort(&f->cells, p) != 0)
        return -1;
    fluid_rates_particles(f);
    f->begun = 1;
    return 0;
}

int64_t sph_fluid_step_end(sph_fluid *f, double dt, const lahar_body_state *states)
{
    sph_particles *p = &f->p;
    if (!f->begun)
        return -1;
    f->begun = 0;
    int64_t cross = fluid_rates_bodies(f, states, dt);
    if (cross < 0)
        return -1;
    const int64_t n = p->n;
    const double hdt = 0.5 * dt;
    const int d3 = f->prm.dim == 3;
#pragma omp parallel for schedule(static) if (n >= SPH_OMP_MIN_LIGHT)
    for (int64_t i = 0; i < n; i++) {
        /* kick (half) with the new rates */
        p->vx[i] = p->vhx[i] + hdt * p->ax[i];
        p->vy[i] = p->vhy[i] + hdt * p->ay[i];
        p->vz[i] = d3 ? p->vhz[i] + hdt * p->az[i] : 0.0;
        p->rho[i] = p->rhoh[i] + hdt * p->drho[i];
    }
    if (f->has_soil)
        fluid_soil_kick(f, hdt, 0);
    f->t += dt;
    f->step++;
    if (f->prm.opt.shepard_interval > 0 && f->step % f->prm.opt.shepard_interval == 0)
        sph_fluid_shepard(f);
    if (f->prm.opt.shifting > 0.0)
        sph_fluid_shift(f);
    f->crossings = cross;
    return cross;
}

int64_t sph_fluid_step(sph_fluid *f, double dt, const lahar_body_state *states)
{
    /* never evaluated: the first rates see the bodies at `states` (step_begin alone would use
     * their own fields) */
    if (!f->primed) {
        if (sph_cells_sort(&f->cells, &f->p) != 0 || sph_fluid_rates(f, states, dt) < 0)
            return -1;
    }
    if (sph_fluid_step_begin(f, dt) != 0)
        return -1;
    return sph_fluid_step_end(f, dt, states);
}

double sph_fluid_dt(const sph_fluid *f)
{
    const sph_params *prm = &f->prm;
    double h = f->k.h;
    double dt = prm->opt.cfl * h / (prm->opt.c0 + f->vmax);
    if (f->has_soil) /* the soil's P-wave speed (sph_soil.h) */
        dt = fmin(dt, prm->opt.cfl * h / (f->soil.cs + f->vmax));
    if (f->has_soil && f->soil.seep > 0.0) /* the seepage drag rate g / k_h (sph_soil.h) */
        dt = fmin(dt, 0.25 * f->soil.mat.kh / f->soil.mat.g_ref);
    if (f->amax > 0.0)
        dt = fmin(dt, prm->opt.cfl_force * sqrt(h / f->amax));
    if (f->nut_max > 0.0) /* SPS: the eddy viscosity adds to the laminar one */
        dt = fmin(dt, prm->opt.cfl_visc * h * h / (prm->opt.mu / prm->rho0 + f->nut_max));
    else if (prm->opt.mu > 0.0)
        dt = fmin(dt, prm->opt.cfl_visc * h * h * prm->rho0 / prm->opt.mu);
    return dt;
}
