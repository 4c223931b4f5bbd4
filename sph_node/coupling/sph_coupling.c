/* SPH-DEM coupling (sph_coupling.h; Trujillo-Vela et al. 2020 section 4). */
#include "sph_coupling.h"
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "geometry.h"
#include "vec.h"

void sph_coupling_set_periodic(sph_coupling *c, const int periodic[3], const double lo[3], const double hi[3])
{
    for (int a = 0; a < 3; a++) {
        c->periodic[a] = periodic && periodic[a] && !(a == 2 && c->dim == 2) && hi[a] > lo[a];
        c->period[a] = c->periodic[a] ? hi[a] - lo[a] : 0.0;
        c->period_lo[a] = c->periodic[a] ? lo[a] : 0.0;
    }
}

/* G(d) = sum over ghost layers at depths s_k = (k + 1/2) dx behind the surface of
 * (1 + s_k/d) dx int_layer W'(r)/r r^2/(r^2 + eta^2) dA, for a particle at distance d in front of it.
 * The layers mirror the fluid lattice (first fluid row at dx/2 in front of the surface, first
 * ghost layer at dx/2 behind it), so for a linear velocity field the fluid rows and the ghosts
 * cancel like a full lattice does; a continuous half-space integral instead leaves 4 % of the wall
 * shear as a spurious force dipole on the first two rows (cubic, h = 1.3 dx). Within a layer the
 * integral is continuous (midpoint rule), since the fluid slides along the wall. */
static double ghost_layers(const kernel *k, int dim, double d, double dx)
{
    const int nt = 2000;
    double S = k->support, eta2 = 0.01 * k->h * k->h, dt = S / nt, g = 0.0;
    for (int l = 0;; l++) {
        double s = (l + 0.5) * dx, y = d + s;
        if (y >= S)
            break;
        double layer = 0.0;
        for (int b = 0; b < nt; b++) {
            double t = (b + 0.5) * dt, r2 = t * t + y * y, r = sqrt(r2);
            if (r >= S)
                break;
            double f = kernel_dwdr(k, r) / r * r2 / (r2 + eta2);
            layer += dim == 2 ? 2.0 * f : 2.0 * M_PI * t * f; /* 2D: both sides of the normal; 3D: ring */
        }
        g += (1.0 + s / d) * layer * dt * dx;
    }
    return g;
}

/* G(d) of ghost_layers for the surface of a disc (2D) or sphere (3D) of radius R (a body whose
 * core is one point): the ghost layer at depth s is the circle or sphere of radius R - s about
 * the centre, at R + d from the particle, and there are none deeper than R. On a flat wall the
 * layers are straight lines or planes; against a disc of radius R they curve away from the
 * particle, and the flat layers over-count the solid within the support by about (d + s)/(2 R) of
 * a layer (6 % for the first rows at R = 12.6 dx, the cylinder array's c = 0.05). Integrated over
 * the polar angle theta about the particle-centre axis; the flat table is the limit R -> inf. */
static double ghost_layers_curved(const kernel *k, int dim, double d, double dx, double R)
{
    const int nt = 2000;
    double S = k->support, eta2 = 0.01 * k->h * k->h, D = R + d, g = 0.0;
    for (int l = 0;; l++) {
        double s = (l + 0.5) * dx, rho = R - s;
        if (d + s >= S || rho <= 0.0)
            break;
        /* theta from 0 to where the layer leaves the support */
        double cmax = (D * D + rho * rho - S * S) / (2.0 * D * rho);
        double tmax = cmax <= -1.0 ? M_PI : acos(cmax > 1.0 ? 1.0 : cmax), dth = tmax / nt, layer = 0.0;
        for (int b = 0; b < nt; b++) {
            double th = (b + 0.5) * dth, r2 = D * D + rho * rho - 2.0 * D * rho * cos(th), r = sqrt(r2);
            if (r >= S || r <= 0.0)
                continue;
            double f = kernel_dwdr(k, r) / r * r2 / (r2 + eta2);
            /* 2D: both sides, arc length rho dtheta; 3D: the ring 2 pi rho sin(theta) rho dtheta */
            layer += dim == 2 ? 2.0 * f * rho : 2.0 * M_PI * rho * rho * sin(th) * f;
        }
        g += (1.0 + s / d) * layer * dth * dx;
    }
    return g;
}

/* ---- LAHAR_SPH_WALL_PRESSURE_GHOST (sph_coupling.h) ----
 * A region of ghosts (volume V_g, pressure p_g = pbar_i + rho_i b.r_g, r_g = x_g - x_i, density
 * rho_i, moving with the wall) adds to particle i (Trujillo-Vela et al. 2020, eq. 2, symmetric pressure term, and eq. 1,
 * continuity):
 *   a = -sum_g V_g (p_i + p_g)/rho_i grad_i W_ig = (p_i + pbar_i)/rho_i A + B b,
 *   drho = rho_i sum_g V_g u_rel.grad_i W_ig = -rho_i u_rel.A,
 *   A = sum_g V_g F r_g,  B = sum_g V_g F r_g r_g^T,  F = W'(r)/r.
 * The sums over the layers are tabulated at setup:
 *  - wall table, frame (n, e, w), r_g = -(d + s_k) n + t e + w w, e up the wall (against the
 *    body force's part along it): the ghosts with t < zeta = pbar_i / (rho_i |b_t|), where p_g
 *    reaches 0. Values {A_n, A_e, B_nn, B_ne, B_ee} on a grid of d and zeta (cumulative in t).
 *  - corner table, frame (n_a, n_b, e = n_a x n_b), r_g = -(d_a + s_k) n_a + t n_b + z e: wall a's
 *    ghosts behind wall b (t < -d_b), z < zeta_e (3D: cut along the edge like the wall table).
 *    Values {A_a, A_b, A_e, B_aa, B_ab, B_ae, B_bb, B_be, B_ee} on a grid of d_a, d_b, zeta_e. */
#define GHOST_NT 48 /* wall table: bins of t per half support; zeta at the 2 GHOST_NT + 1 bin edges */
#define GHOST_NZ 24 /* corner table (3D): bins of z per half support */

/* One column of the wall table (distance d): out[j * 5 + v] for zeta_j = -S + j S / GHOST_NT. */
static void ghost_wall_column(const kernel *k, int dim, double d, double dx, double *out)
{
    const int nw = dim == 3 ? GHOST_NT : 1;
    const double S = k->support, dt = S / GHOST_NT, dw = S / GHOST_NT;
    for (int v = 0; v < 5; v++)
        out[v] = 0.0;
    for (int j = 0; j < 2 * GHOST_NT; j++) {
        double t = -S + (j + 0.5) * dt, bin[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
        for (int l = 0;; l++) {
            double y = d + (l + 0.5) * dx;
            if (y >= S)
                break;
            for (int c = 0; c < nw; c++) {
                double w = dim == 3 ? (c + 0.5) * dw : 0.0, r = sqrt(y * y + t * t + w * w);
                if (r >= S)
                    continue;
                double fv = kernel_dwdr(k, r) / r * dt * dx * (dim == 3 ? 2.0 * dw : 1.0); /* F V_g, w of both signs */
                bin[0] -= fv * y;
                bin[1] += fv * t;
                bin[2] += fv * y * y;
                bin[3] -= fv * y * t;
                bin[4] += fv * t * t;
            }
        }
        for (int v = 0; v < 5; v++)
            out[(j + 1) * 5 + v] = out[j * 5 + v] + bin[v];
    }
}

/* One column of the corner table (d_a, d_b): out[j * 9 + v] for zeta_e at the z bin edges (3D),
 * or out[9 + v] the whole sum (2D, out[v] = 0). */
static void ghost_corner_column(const kernel *k, int dim, double da, double db, double dx, double *out)
{
    const int nz = dim == 3 ? 2 * GHOST_NZ : 1, nt = GHOST_NT;
    const double S = k->support, dz = S / GHOST_NZ;
    for (int v = 0; v < 9; v++)
        out[v] = 0.0;
    for (int j = 0; j < nz; j++) {
        double z = dim == 3 ? -S + (j + 0.5) * dz : 0.0, bin[9] = {0.0};
        for (int l = 0; db < S; l++) {
            double y = da + (l + 0.5) * dx, wt = (S - db) / nt;
            if (y >= S)
                break;
            for (int b = 0; b < nt; b++) {
                double t = -db - (b + 0.5) * wt, r = sqrt(y * y + t * t + z * z);
                if (r >= S)
                    continue;
                double fv = kernel_dwdr(k, r) / r * wt * dx * (dim == 3 ? dz : 1.0), rg[3] = {-y, t, z};
                bin[0] += fv * rg[0], bin[1] += fv * rg[1], bin[2] += fv * rg[2];
                bin[3] += fv * rg[0] * rg[0], bin[4] += fv * rg[0] * rg[1], bin[5] += fv * rg[0] * rg[2];
                bin[6] += fv * rg[1] * rg[1], bin[7] += fv * rg[1] * rg[2], bin[8] += fv * rg[2] * rg[2];
            }
        }
        for (int v = 0; v < 9; v++)
            out[(j + 1) * 9 + v] = out[j * 9 + v] + bin[v];
    }
}

/* The ghost tables (wall and corner), once, for the water's or the soil's ghosts. */
static int ghost_tables(sph_coupling *c, double dx)
{
    if (c->wtab)
        return 0;
    const int nd = SPH_COUPLING_WTAB + 1, nq = SPH_COUPLING_QTAB + 1, nzw = 2 * GHOST_NT + 1;
    const int nzq = c->dim == 3 ? 2 * GHOST_NZ + 1 : 2;
    c->wtab = calloc((size_t)nd * nzw * 5, sizeof *c->wtab);
    c->qtab = calloc((size_t)nq * nq * nzq * 9, sizeof *c->qtab);
    if (!c->wtab || !c->qtab) {
        free(c->wtab), free(c->qtab);
        c->wtab = c->qtab = NULL;
        return -1;
    }
    c->wtab_dd = (c->k.support - c->gtab_d0) / SPH_COUPLING_WTAB;
    c->qtab_dd = (c->k.support - c->gtab_d0) / SPH_COUPLING_QTAB;
    for (int i = 0; i < nd; i++)
        ghost_wall_column(&c->k, c->dim, c->gtab_d0 + i * c->wtab_dd, dx, c->wtab + (size_t)i * nzw * 5);
    for (int i = 0; i < nq; i++)
        for (int j = 0; j < nq; j++)
            ghost_corner_column(&c->k, c->dim, c->gtab_d0 + i * c->qtab_dd, c->gtab_d0 + j * c->qtab_dd, dx,
                                c->qtab + ((size_t)i * nq + j) * nzq * 9);
    return 0;
}

int sph_coupling_set_wall_pressure(sph_coupling *c, lahar_sph_wall_pressure mode, const double body_force[3], double dx)
{
    c->pressure = mode;
    for (int a = 0; a < 3; a++)
        c->body_force[a] = body_force[a];
    if (mode != LAHAR_SPH_WALL_PRESSURE_GHOST)
        return 0;
    if (ghost_tables(c, dx) != 0) {
        c->pressure = LAHAR_SPH_WALL_PRESSURE_PENALTY;
        return -1;
    }
    return 0;
}

int sph_coupling_set_soil_wall(sph_coupling *c, lahar_sph_wall_pressure mode, const double gravity[3], double dx)
{
    c->soil_pressure = mode;
    for (int a = 0; a < 3; a++)
        c->soil_g[a] = gravity[a];
    if (mode != LAHAR_SPH_WALL_PRESSURE_GHOST)
        return 0;
    if (!c->soil_lw)
        c->soil_lw = calloc((size_t)c->pcap, sizeof *c->soil_lw);
    if (!c->soil_lw_on)
        c->soil_lw_on = calloc((size_t)c->pcap, 1);
    if (!c->soil_lw || !c->soil_lw_on || ghost_tables(c, dx) != 0) {
        c->soil_pressure = LAHAR_SPH_WALL_PRESSURE_PENALTY;
        return -1;
    }
    return 0;
}

/* Grid coordinate of x on [x0, x0 + n dx]: index and fraction; 0 when beyond the top (the caller
 * treats it as outside), clamped at the bottom. */
static int ghost_grid(double x, double x0, double dx, int n, int *i, double *f)
{
    double u = (x - x0) / dx;
    if (u >= n)
        return 0;
    if (!(u > 0.0))
        u = 0.0;
    *i = (int)u < n ? (int)u : n - 1;
    *f = u - *i;
    return 1;
}

/* Cut coordinate zeta (height up direction e where the ghost pressure reaches 0) on the edges
 * -S .. S in nbin bins per half: index and fraction, clamped at both ends. */
static void ghost_cut_grid(double zeta, double S, int nbin, int *j, double *f)
{
    double u = (zeta + S) / (S / nbin);
    if (!(u > 0.0)) /* below -S (or NaN): nothing */
        u = 0.0;
    if (u >= 2 * nbin)
        u = 2 * nbin - 1e-9;
    *j = (int)u;
    *f = u - *j;
}

/* Direction e up along the plane of normal n (against the body force's part in it) and the
 * height zeta = p / (rho |b_t|) where the extrapolated ghost pressure reaches 0; e = 0 and zeta
 * beyond the support when the body force is along n. */
static double ghost_cut(const sph_coupling *c, vec3 n, double p, double rho, vec3 *e)
{
    vec3 b = v3_load(c->body_force), bt = v3_axpy(-v3_dot(b, n), n, b);
    double bmag = v3_norm(bt);
    if (!(bmag > 1e-9 * v3_norm(b))) {
        *e = v3(0, 0, 0);
        return 2.0 * c->k.support;
    }
    *e = v3_scale(bt, -1.0 / bmag);
    return p / (rho * bmag);
}

/* A particle (p, rho, relative velocity u) at distance d from a flat wall of normal n: ghost
 * pressure acceleration, continuity rate in *drho. */
static vec3 ghost_wall_accel(const sph_coupling *c, double p, double pbar, double rho, double d, vec3 n, vec3 u,
                             double *drho)
{
    const int nzw = 2 * GHOST_NT + 1;
    int i, j;
    double fi, fj, K[5];
    *drho = 0.0;
    if (!ghost_grid(d, c->gtab_d0, c->wtab_dd, SPH_COUPLING_WTAB, &i, &fi))
        return v3(0, 0, 0);
    vec3 e;
    double zeta = ghost_cut(c, n, pbar, rho, &e);
    ghost_cut_grid(zeta, c->k.support, GHOST_NT, &j, &fj);
    const double *t00 = c->wtab + ((size_t)i * nzw + j) * 5, *t01 = t00 + 5, *t10 = t00 + (size_t)nzw * 5,
                 *t11 = t10 + 5;
    for (int v = 0; v < 5; v++)
        K[v] = (1 - fi) * ((1 - fj) * t00[v] + fj * t01[v]) + fi * ((1 - fj) * t10[v] + fj * t11[v]);
    vec3 b = v3_load(c->body_force);
    double bn = v3_dot(b, n), be = v3_dot(b, e), pp = (p + pbar) / rho;
    *drho = -rho * (K[0] * v3_dot(u, n) + K[1] * v3_dot(u, e));
    return v3_axpy(pp * K[1] + K[3] * bn + K[4] * be, e, v3_scale(n, pp * K[0] + K[2] * bn + K[3] * be));
}

/* The ghosts' reference pressure for particle i: the Shepard mean over i and its neighbours of
 * their pressures carried to x_i hydrostatically, sum_j V_j W_ij (p_j + rho_j b.(x_i - x_j)) /
 * sum_j V_j W_ij (Adami, Hu & Adams 2012, eq. 27). Mirroring p_i alone lets a particle's own
 * pressure push it off the wall into the fluid, which compresses it further (unstable). */
static double ghost_pbar(const sph_coupling *c, const sph_particles *p, int64_t i)
{
    const kernel *k = &c->k;
    if (!c->cells) /* coupling used without the fluid's cells: the particle's own pressure */
        return p->p[i];
    const double s2 = k->support * k->support, bx = c->body_force[0], by = c->body_force[1], bz = c->body_force[2];
    double vw = p->m[i] / p->rho[i] * kernel_w(k, 0.0), num = vw * p->p[i], den = vw;
    SPH_FOR_EACH_NEIGHBOUR(c->cells, p, i, p->x[i], p->y[i], p->z[i], s2, {
        double w = p->m[j] / p->rho[j] * kernel_w(k, sqrt(r2));
        num += w * (p->p[j] + p->rho[j] * (bx * rx + by * ry + bz * rz));
        den += w;
    });
    return num / den;
}

/* The soil ghosts' reference stress for soil particle i (sph_coupling_set_soil_wall): the Shepard
 * mean over i and its soil neighbours of sigma_j - rho_j g.(x_i - x_j) I (tension positive, so the
 * water's p_j + rho_j b.x_ij with p = -sigma). */
static void ghost_soil_sigbar(const sph_coupling *c, const sph_particles *p, int64_t i, double out[SPH_NSTRESS])
{
    for (int a = 0; a < SPH_NSTRESS; a++)
        out[a] = p->sig[a][i];
    if (!c->cells)
        return;
    const kernel *k = &c->k;
    const double s2 = k->support * k->support, gx = c->soil_g[0], gy = c->soil_g[1], gz = c->soil_g[2];
    double vw = p->m[i] / p->rho[i] * kernel_w(k, 0.0), den = vw, num[SPH_NSTRESS];
    for (int a = 0; a < SPH_NSTRESS; a++)
        num[a] = vw * p->sig[a][i];
    SPH_FOR_EACH_NEIGHBOUR(c->cells, p, i, p->x[i], p->y[i], p->z[i], s2, {
        if (p->phase[j] == 0)
            continue;
        double w = p->m[j] / p->rho[j] * kernel_w(k, sqrt(r2)), dg = p->rho[j] * (gx * rx + gy * ry + gz * rz);
        for (int a = 0; a < SPH_NSTRESS; a++)
            num[a] += w * p->sig[a][j];
        num[0] -= w * dg, num[3] -= w * dg, num[5] -= w * dg; /* xx, yy, zz */
        den += w;
    });
    for (int a = 0; a < SPH_NSTRESS; a++)
        out[a] = num[a] / den;
}

/* sigma (xx, xy, xz, yy, yz, zz) times the vector u. */
static vec3 sym_mul(const double s[SPH_NSTRESS], vec3 u)
{
    return v3(s[0] * u.x + s[1] * u.y + s[2] * u.z, s[1] * u.x + s[3] * u.y + s[4] * u.z,
              s[2] * u.x + s[4] * u.y + s[5] * u.z);
}

/* The soil ghosts' acceleration (sph_coupling_set_soil_wall) on a soil particle of stress si,
 * reference stress sbar and density rho at distance d from a flat wall of normal n. */
static vec3 ghost_soil_accel(const sph_coupling *c, const double si[SPH_NSTRESS], const double sbar[SPH_NSTRESS],
                             double rho, double d, vec3 n, vec3 *A)
{
    *A = v3(0, 0, 0);
    const int nzw = 2 * GHOST_NT + 1;
    int i, j;
    double fi, fj, K[5], S[SPH_NSTRESS];
    if (!ghost_grid(d, c->gtab_d0, c->wtab_dd, SPH_COUPLING_WTAB, &i, &fi))
        return v3(0, 0, 0);
    vec3 g = v3_load(c->soil_g), gt = v3_axpy(-v3_dot(g, n), n, g), e = v3(0, 0, 0);
    double gmag = v3_norm(gt), zeta = 2.0 * c->k.support;
    double snn = v3_dot(n, sym_mul(sbar, n));
    if (gmag > 1e-9 * v3_norm(g)) { /* the cut where the ghosts' normal stress reaches 0 (ghost_cut) */
        e = v3_scale(gt, -1.0 / gmag);
        zeta = -snn / (rho * gmag);
    }
    ghost_cut_grid(zeta, c->k.support, GHOST_NT, &j, &fj);
    const double *t00 = c->wtab + ((size_t)i * nzw + j) * 5, *t01 = t00 + 5, *t10 = t00 + (size_t)nzw * 5,
                 *t11 = t10 + 5;
    for (int v = 0; v < 5; v++)
        K[v] = (1 - fi) * ((1 - fj) * t00[v] + fj * t01[v]) + fi * ((1 - fj) * t10[v] + fj * t11[v]);
    for (int a = 0; a < SPH_NSTRESS; a++)
        S[a] = si[a] + sbar[a];
    /* the push along n only: -(S.A)_n / rho + (B g)_n with A = K0 n + K1 e and the shear across the
     * wall (S_ne) taken out. The part along the wall, -K1 S_ee / rho + (B g)_e, is left out: on a
     * full flat wall it vanishes (K1 = K3 = 0), and where the ghosts are cut (a side wall, cut
     * where the normal stress reaches 0) it would take the soil's vertical stress S_ee, which
     * does not vanish there, against a one-sided ghost region: a spurious push along the wall
     * that made a collapsing column unstable. */
    double s_nn = v3_dot(n, sym_mul(S, n)), gn = v3_dot(g, n), ge = v3_dot(g, e);
    *A = v3_axpy(K[1], e, v3_scale(n, K[0]));
    return v3_scale(n, -K[0] * s_nn / rho + K[2] * gn + K[3] * ge);
}

/* The corner correction: half of wall a's ghosts behind the perpendicular wall b (corner table),
 * the acceleration and continuity rate to take off. In the continuity rate the quadrant moves
 * along n_a with wall a and along n_b with wall b (urel_a, urel_b: the particle's velocity
 * relative to each wall's surface): each wall is impermeable along its own normal only. With wall
 * a's velocity along n_b too, a lid sliding along n_b into a fixed side wall b made its corner a
 * source or a sink of volume (lid_driven_cavity_2d, ghost walls: -0.87 % of the box in 30 s;
 * cases/README.md). Both the same for fixed walls. */
static vec3 ghost_corner_accel(const sph_coupling *c, double p, double pbar, double rho, double da, vec3 na,
                               double db, vec3 nb, vec3 urel_a, vec3 urel_b, double *drho)
{
    const int nq = SPH_COUPLING_QTAB + 1, nzq = c->dim == 3 ? 2 * GHOST_NZ + 1 : 2;
    int i, j, k = 0;
    double fi, fj, fk = 1.0, Q[9];
    *drho = 0.0;
    if (!ghost_grid(da, c->gtab_d0, c->qtab_dd, SPH_COUPLING_QTAB, &i, &fi) ||
        !ghost_grid(db, c->gtab_d0, c->qtab_dd, SPH_COUPLING_QTAB, &j, &fj))
        return v3(0, 0, 0);
    vec3 b = v3_load(c->body_force), e = v3_normalize(v3_cross(na, nb));
    if (v3_dot(b, e) > 0.0)
        e = v3_neg(e);
    if (c->dim == 3) {
        double be = -v3_dot(b, e);
        ghost_cut_grid(be > 1e-9 * v3_norm(b) ? pbar / (rho * be) : 2.0 * c->k.support, c->k.support, GHOST_NZ, &k, &fk);
    }
    for (int v = 0; v < 9; v++) {
        double q = 0.0;
        for (int a = 0; a < 2; a++)
            for (int bb = 0; bb < 2; bb++)
                for (int cc = 0; cc < 2; cc++) {
                    double w = (a ? fi : 1 - fi) * (bb ? fj : 1 - fj) * (cc ? fk : 1 - fk);
                    if (w != 0.0)
                        q += w * c->qtab[(((size_t)(i + a) * nq + (size_t)(j + bb)) * nzq + (size_t)(k + cc)) * 9 + v];
                }
        Q[v] = q;
    }
    double bf[3] = {v3_dot(b, na), v3_dot(b, nb), v3_dot(b, e)}, pp = (p + pbar) / rho;
    double ax = pp * Q[0] + Q[3] * bf[0] + Q[4] * bf[1] + Q[5] * bf[2];
    double ay = pp * Q[1] + Q[4] * bf[0] + Q[6] * bf[1] + Q[7] * bf[2];
    double az = pp * Q[2] + Q[5] * bf[0] + Q[7] * bf[1] + Q[8] * bf[2];
    *drho = -0.5 * rho * (Q[0] * v3_dot(urel_a, na) + Q[1] * v3_dot(urel_b, nb) + Q[2] * v3_dot(urel_a, e));
    return v3_scale(v3_add(v3_add(v3_scale(na, ax), v3_scale(nb, ay)), v3_scale(e, az)), 0.5);
}
static double coupling_gtab_lookup(const sph_coupling *c, const double *tab, double d)
{
    double u = (d - c->gtab_d0) / c->gtab_dd;
    if (!(u > 0.0))
        return tab[0];
    if (u >= SPH_COUPLING_GTAB)
        return 0.0;
    int i = (int)u;
    double f = u - i;
    return (1.0 - f) * tab[i] + f * tab[i + 1];
}

double sph_coupling_halfspace_factor(const sph_coupling *c, double d)
{
    return coupling_gtab_lookup(c, c->gtab, d);
}

double sph_coupling_body_halfspace_factor(const sph_coupling *c, int b, double d)
{
    return coupling_gtab_lookup(c, c->gtab_body && c->gtab_body[b] ? c->gtab_body[b] : c->gtab, d);
}

int sph_coupling_init(sph_coupling *c, int dim, int nbody, const lahar_body *bodies, const kernel *k, double dx,
                      double m_sph, double mu, lahar_sph_wall_viscous viscous, int64_t particle_cap)
{
    memset(c, 0, sizeof *c);
    c->dim = dim;
    c->nbody = nbody;
    c->bodies = bodies;
    c->k = *k;
    c->eps = 0.5 * dx;
    c->mu = mu;
    c->viscous = viscous;
    c->m_min = m_sph;
    for (int b = 0; b < nbody; b++)
        if (bodies[b].motion == LAHAR_MOTION_FREE && bodies[b].mass > 0.0 && bodies[b].mass < c->m_min)
            c->m_min = bodies[b].mass;
    c->pcap = particle_cap < 1 ? 1 : particle_cap;
    int nb = nbody > 0 ? nbody : 1;
    c->bound = calloc((size_t)nb, sizeof *c->bound);
    c->grid = calloc((size_t)nb, sizeof *c->grid);
    c->box = calloc((size_t)nb, sizeof *c->box);
    c->has_grid = calloc((size_t)nb, sizeof *c->has_grid);
    c->force = calloc((size_t)nb, sizeof *c->force);
    c->torque = calloc((size_t)nb, sizeof *c->torque);
    c->body_start = calloc((size_t)nb + 1, sizeof *c->body_start);
    c->body_fill = calloc((size_t)nb, sizeof *c->body_fill);
    c->slot_n = calloc((size_t)c->pcap, sizeof *c->slot_n);
    c->near = calloc((size_t)c->pcap, sizeof *c->near);
    c->slot_body = calloc((size_t)c->pcap * SPH_COUPLING_MAX_PER_PARTICLE, sizeof *c->slot_body);
    c->slot = calloc((size_t)c->pcap * SPH_COUPLING_MAX_PER_PARTICLE, sizeof *c->slot);
    c->contacts_cap = 1024;
    c->contacts = calloc((size_t)c->contacts_cap, sizeof *c->contacts);
    if (!c->bound || !c->box || !c->grid || !c->has_grid || !c->force || !c->torque || !c->body_start || !c->body_fill || !c->slot_n || !c->slot_body ||
        !c->slot || !c->contacts) {
        sph_coupling_free(c);
        return -1;
    }
    for (int b = 0; b < nbody; b++) {
        const lahar_shape *s = &bodies[b].shape;
        double r = 0.0;
        for (int i = 0; i < s->nv; i++)
            r = fmax(r, v3_norm(v3_load(s->v[i])));
        c->bound[b] = r + s->radius;
        /* fixed bodies never move: a tight world box culls most particles (long walls) */
        for (int a = 0; a < 3; a++) {
            c->box[b][a] = s->nv ? INFINITY : -INFINITY;
            c->box[b][3 + a] = s->nv ? -INFINITY : INFINITY;
        }
        for (int i = 0; i < s->nv; i++) {
            vec3 w = geom_world_vertex(s, bodies[b].x, bodies[b].q, i);
            for (int a = 0; a < 3; a++) {
                c->box[b][a] = fmin(c->box[b][a], v3_get(w, a) - s->radius);
                c->box[b][3 + a] = fmax(c->box[b][3 + a], v3_get(w, a) + s->radius);
            }
        }
        if (s->nv + s->ne + s->nf > SPH_COUPLING_GRID_FEATURES) {
            if (geom_feature_grid_build(&c->grid[b], s) != 0) {
                sph_coupling_free(c);
                return -1;
            }
            c->has_grid[b] = 1;
        }
    }
    /* the half-space factor, tabulated from eps/2 (closest a particle is let near) to the support */
    c->gtab_d0 = 0.5 * c->eps;
    c->gtab_dd = (k->support - c->gtab_d0) / SPH_COUPLING_GTAB;
    for (int i = 0; i <= SPH_COUPLING_GTAB; i++)
        c->gtab[i] = ghost_layers(k, dim, c->gtab_d0 + i * c->gtab_dd, dx);
    /* discs and spheres (one core point): their own table, layers curved with the surface */
    for (int b = 0; b < nbody; b++) {
        const lahar_shape *s = &bodies[b].shape;
        if (s->nv != 1 || s->ne != 0 || s->nf != 0 || !(s->radius > 0.0))
            continue;
        if (!c->gtab_body) {
            c->gtab_body = calloc((size_t)nb, sizeof *c->gtab_body);
            if (!c->gtab_body) {
                sph_coupling_free(c);
                return -1;
            }
        }
        c->gtab_body[b] = malloc((SPH_COUPLING_GTAB + 1) * sizeof **c->gtab_body);
        if (!c->gtab_body[b]) {
            sph_coupling_free(c);
            return -1;
        }
        for (int i = 0; i <= SPH_COUPLING_GTAB; i++)
            c->gtab_body[b][i] = ghost_layers_curved(k, dim, c->gtab_d0 + i * c->gtab_dd, dx, s->radius);
    }
    return 0;
}

void sph_coupling_free(sph_coupling *c)
{
    for (int b = 0; c->has_grid && b < c->nbody; b++)
        if (c->has_grid[b])
            geom_feature_grid_free(&c->grid[b]);
    free(c->grid);
    free(c->box);
    free(c->has_grid);
    for (int b = 0; c->gtab_body && b < c->nbody; b++)
        free(c->gtab_body[b]);
    free(c->gtab_body);
    free(c->bound);
    free(c->force);
    free(c->torque);
    free(c->body_start);
    free(c->body_fill);
    free(c->slot_n);
    free(c->near);
    free(c->slot_body);
    free(c->slot);
    free(c->contacts);
    free(c->soil_hist_body);
    free(c->soil_hist_d);
    free(c->wtab);
    free(c->qtab);
    free(c->soil_lw);
    free(c->soil_lw_on);
    memset(c, 0, sizeof *c);
}

int sph_coupling_enable_soil(sph_coupling *c, double mu_phi)
{
    const size_t n = (size_t)c->pcap * SPH_COUPLING_MAX_PER_PARTICLE;
    free(c->soil_hist_body);
    free(c->soil_hist_d);
    c->soil_hist_body = malloc(n * sizeof *c->soil_hist_body);
    c->soil_hist_d = calloc(n, sizeof *c->soil_hist_d);
    if (!c->soil_hist_body || !c->soil_hist_d) {
        free(c->soil_hist_body), free(c->soil_hist_d);
        c->soil_hist_body = NULL, c->soil_hist_d = NULL;
        return -1;
    }
    for (size_t k = 0; k < n; k++)
        c->soil_hist_body[k] = -1;
    c->mu_phi = mu_phi;
    return 0;
}

/* The tangential spring of soil particle `id` on body b (sph_coupling.h, eq. 22-25): from its
 * last value (0 for a new pair) to this step's, capped; returns the tangential force on the
 * particle, -K_n delta_tau*, and the new spring in d_out. */
static vec3 coupling_soil_tangential(const sph_coupling *c, int64_t id, int b, vec3 n, vec3 urel, double fn, double kn,
                                     double dt, double d_out[3])
{
    vec3 d = v3(0, 0, 0);
    const int64_t base = id * SPH_COUPLING_MAX_PER_PARTICLE;
    for (int s = 0; s < SPH_COUPLING_MAX_PER_PARTICLE; s++)
        if (c->soil_hist_body[base + s] == b)
            d = v3_load(c->soil_hist_d[base + s]);
    d = v3_sub(d, v3_scale(n, v3_dot(d, n)));          /* onto the current tangent plane */
    vec3 ut = v3_sub(urel, v3_scale(n, v3_dot(urel, n))); /* eq. 22 */
    d = v3_axpy(dt, ut, d);                             /* eq. 23 */
    double len = v3_norm(d), lim = c->mu_phi * fn / kn;
    if (len > lim)                                      /* eq. 24: slip */
        d = len > 0.0 ? v3_scale(d, lim / len) : v3(0, 0, 0);
    v3_store(d, d_out);
    return v3_scale(d, -kn);                            /* eq. 25 */
}

void sph_coupling_mark(sph_coupling *c, const sph_cells *cells, int64_t n, const lahar_body_state *states)
{
    c->near_valid = 0;
    if (!c->near || c->nbody >= 32 || c->periodic[0] || c->periodic[1] || c->periodic[2] || n > c->pcap ||
        cells->periodic[0] || cells->periodic[1] || cells->periodic[2])
        return;
    memset(c->near, 0, (size_t)n * sizeof *c->near);
    const double support = c->k.support;
    const int d3 = cells->dim == 3;
    for (int b = 0; b < c->nbody; b++) {
        const lahar_body *body = &c->bodies[b];
        const int fixed = body->motion == LAHAR_MOTION_FIXED;
        const double *bx = !fixed && states ? states[b].x : body->x;
        double lo[3], hi[3];
        int all = 0;
        for (int a = 0; a < 3; a++) {
            lo[a] = (fixed ? c->box[b][a] : bx[a] - c->bound[b]) - support;
            hi[a] = (fixed ? c->box[b][3 + a] : bx[a] + c->bound[b]) + support;
            all |= !isfinite(lo[a]) || !isfinite(hi[a]);
        }
        const uint32_t bit = 1u << b;
        if (all) { /* no finite box: every particle may be near it */
            for (int64_t i = 0; i < n; i++)
                c->near[i] |= bit;
            continue;
        }
        /* the cells are bounded by the particles: a box that misses the grid marks nothing */
        int miss = 0;
        for (int a = 0; a < (d3 ? 3 : 2); a++)
            miss |= hi[a] < cells->lo[a] || lo[a] > cells->lo[a] + cells->nc[a] * cells->size[a];
        if (miss)
            continue;
        /* the cell of a coordinate is monotone in it (sph_cells_coord, clamped): a particle inside
         * [lo, hi] along an axis lies in a cell between those of lo and hi */
        const int x0 = sph_cells_coord(cells, 0, lo[0]), x1 = sph_cells_coord(cells, 0, hi[0]);
        const int y0 = sph_cells_coord(cells, 1, lo[1]), y1 = sph_cells_coord(cells, 1, hi[1]);
        const int z0 = d3 ? sph_cells_coord(cells, 2, lo[2]) : 0, z1 = d3 ? sph_cells_coord(cells, 2, hi[2]) : 0;
        for (int z = z0; z <= z1; z++)
            for (int y = y0; y <= y1; y++) {
                const int64_t row = ((int64_t)z * cells->nc[1] + y) * cells->nc[0];
                for (int64_t i = cells->start[row + x0]; i < cells->start[row + x1 + 1]; i++)
                    c->near[i] |= bit;
            }
    }
    c->near_valid = 1;
}

int64_t sph_coupling_apply(sph_coupling *c, sph_particles *p, const lahar_body_state *states, double dt)
{
    const int64_t n = p->n;
    const double support = c->k.support;
    /* eq. 15: K_n = 0.1 m_min / dt^2; with kn_dt > 0 the acoustic step instead (sph_coupling.h) */
    const double dtk = c->kn_dt > 0.0 ? c->kn_dt : dt;
    const double kn = 0.1 * c->m_min / (dtk * dtk);
    c->kn = kn;
    const double w0 = kernel_w(&c->k, 0.0), hd = pow(c->k.h, c->dim);
    if (n > c->pcap)
        return -1;

    const int near_valid = c->near_valid && c->nbody < 32;
    c->near_valid = 0; /* the marks serve this evaluation only */
#pragma omp parallel for schedule(dynamic, SPH_OMP_CHUNK) if (n >= SPH_OMP_MIN_HEAVY)
    for (int64_t i = 0; i < n; i++) {
        int ns = 0;
        const vec3 xp = v3(p->x[i], p->y[i], p->z[i]);
        vec3 ftot = v3(0, 0, 0);
        /* soil-DEM springs of this evaluation (sph_coupling_enable_soil) */
        const int soil = p->phase[i] != 0 && c->soil_hist_body;
        int nh = 0, hist_b[SPH_COUPLING_MAX_PER_PARTICLE];
        double hist_d[SPH_COUPLING_MAX_PER_PARTICLE][3];
        vec3 gn[SPH_COUPLING_MAX_PER_PARTICLE]; /* ghost pressure: normal and distance per contact */
        double gd[SPH_COUPLING_MAX_PER_PARTICLE], drho_g = 0.0, pbar = NAN;
        double sbar[SPH_NSTRESS] = {0.0}, sown[SPH_NSTRESS] = {0.0}; /* soil ghosts (sph_coupling_set_soil_wall) */
        double lw[9] = {0.0}; /* their share of the velocity gradient */
        int have_sbar = 0;
        vec3 gu[SPH_COUPLING_MAX_PER_PARTICLE];
        const uint32_t near = near_valid ? c->near[i] : ~0u;
        for (int b = 0; b < c->nbody && ns < SPH_COUPLING_MAX_PER_PARTICLE; b++) {
            if (!(near >> b & 1u)) /* sph_coupling_mark: this body is out of reach */
                continue;
            const lahar_body *body = &c->bodies[b];
            const lahar_body_state *st = states && body->motion != LAHAR_MOTION_FIXED ? &states[b] : NULL;
            const double *bx = st ? st->x : body->x, *bq = st ? st->q : body->q;
            const double *bv = st ? st->v : body->v, *bw = st ? st->w : body->w;
            vec3 xb = v3_load(bx);
            const double R = body->shape.radius;
            /* periodic images (sph_coupling_set_periodic): the particle shifted by n whole periods
             * towards the body, for every n along each periodic axis that brings it within the
             * body's range plus the support; the contact then lies on the body itself. A body as
             * long as the period along an axis (a channel's wall) overlaps its own images: it
             * spans that axis and has none along it, as without images; a body outside the period
             * (plus the support) is outside the domain and has none either. */
            int nlo[3] = {0, 0, 0}, nhi[3] = {0, 0, 0};
            for (int a = 0; a < 3; a++) {
                if (!c->periodic[a])
                    continue;
                /* the range of the body along a: its world box when fixed (tight), else its sphere */
                const double *bb = c->box[b];
                int boxed = body->motion == LAHAR_MOTION_FIXED && isfinite(bb[a]) && isfinite(bb[3 + a]);
                double lo = boxed ? bb[a] : bx[a] - c->bound[b], hi = boxed ? bb[3 + a] : bx[a] + c->bound[b];
                double xa = v3_get(xp, a);
                const double plo = c->period_lo[a], phi = plo + c->period[a];
                if (c->periodic[a] && hi - lo < c->period[a] && hi > plo - support && lo < phi + support &&
                    isfinite(xa)) {
                    nlo[a] = (int)ceil((xa - hi - support) / c->period[a]);
                    nhi[a] = (int)floor((xa - lo + support) / c->period[a]);
                }
            }
            const int nx = nhi[0] - nlo[0] + 1, ny = nhi[1] - nlo[1] + 1, nimg = nx * ny * (nhi[2] - nlo[2] + 1);
            for (int img = 0; img < nimg && ns < SPH_COUPLING_MAX_PER_PARTICLE; img++) {
                /* without images (ix = iy = iz = 0) xi is the particle's position bit for bit; the
                 * divisions only where there are several images (most particles have one) */
                const int ix = nlo[0] + (nimg > 1 ? img % nx : 0), iy = nlo[1] + (nimg > 1 ? img / nx % ny : 0),
                          iz = nlo[2] + (nimg > 1 ? img / (nx * ny) : 0);
                vec3 xi = v3(xp.x - ix * c->period[0], xp.y - iy * c->period[1], xp.z - iz * c->period[2]);
                /* culling, cheapest test first (a particle culled here is at least the support from
                 * the surface, so the tests' order and form change no result): fixed bodies have
                 * a tight world box, every body a bounding sphere (fixed bodies keep world-frame
                 * vertices, x = origin of that frame) */
                if (body->motion == LAHAR_MOTION_FIXED) {
                    const double *bb = c->box[b];
                    if (xi.x < bb[0] - support || xi.x > bb[3] + support || xi.y < bb[1] - support ||
                        xi.y > bb[4] + support || xi.z < bb[2] - support || xi.z > bb[5] + support)
                        continue;
                }
                const double reach = c->bound[b] + support;
                if (v3_norm2(v3_sub(xi, xb)) > reach * reach)
                    continue;
                vec3 core = xb;
                /* big shapes (terrain, flumes): only the features near the particle */
                double dc = c->has_grid[b] ? geom_point_body_core_near(&c->grid[b], &body->shape, bx, bq, xi, R + support,
                                                                       &core, NULL)
                                           : geom_point_body_core(&body->shape, bx, bq, xi, &core, NULL);
                int inside = geom_point_in_core(&body->shape, body->convex, c->dim, bx, bq, xi); /* deep inside: far from the surface */
                if (dc - R >= support && !inside)
                    continue;
                if (dc == DBL_MAX) /* inside a big closed core, far from every feature: no direction */
                    dc = 0.0;
                int cross = inside || dc < R;
                vec3 nrm;
                double d;
                if (dc > 0.0) {
                    nrm = v3_scale(v3_sub(xi, core), 1.0 / dc);
                    d = dc - R; /* eq. 13, signed */
                    if (inside) {
                        nrm = v3_neg(nrm);
                        d = -dc - R;
                    }
                } else {
                    nrm = v3(0, 0, 0); /* on the core: no direction to push; counted as a crossing */
                    d = -R;
                }
                vec3 xs = v3_axpy(R, nrm, core);         /* eq. 12 */
                double delta = c->eps - d;               /* eq. 14 */
                vec3 fn = delta > 0.0 ? v3_scale(nrm, kn * delta) : v3(0, 0, 0); /* eq. 15 */
                /* eq. 16: relative velocity to the body's surface at x_s */
                vec3 urel = v3_sub(v3(p->vx[i], p->vy[i], p->vz[i]),
                                   v3_add(v3_load(bv), v3_cross(v3_load(bw), v3_sub(xs, xb))));
                double dv = fmax(d, 0.5 * c->eps); /* the viscous term's distance, kept off zero */
                double coef;
                if (c->viscous == LAHAR_SPH_WALL_HALFSPACE)
                    coef = 2.0 * c->mu / p->rho[i] * sph_coupling_body_halfspace_factor(c, b, dv);
                else /* eq. 17 as printed */
                    coef = 4.0 * p->m[i] / (3.0 * hd) * (2.0 * c->mu) / (4.0 * p->rho[i] * p->rho[i]) / dv *
                           kernel_dwdr(&c->k, dv) / w0;
                /* m_i a_tau (eq. 19) for water; soil: the frictional force of section 4.2 */
                vec3 ft = p->phase[i] == 0 ? v3_scale(urel, p->m[i] * coef) : v3(0, 0, 0);
                /* soil ghost stress (sph_coupling_set_soil_wall): its push along n joins F_n of
                 * the friction cap */
                vec3 fg = v3(0, 0, 0);
                double fgn = 0.0;
                if (p->phase[i] != 0 && c->soil_pressure == LAHAR_SPH_WALL_PRESSURE_GHOST && !cross && p->sig[0]) {
                    if (!have_sbar) {
                        ghost_soil_sigbar(c, p, i, sbar);
                        for (int a = 0; a < SPH_NSTRESS; a++)
                            sown[a] = p->sig[a][i];
                        have_sbar = 1;
                    }
                    vec3 A;
                    fg = v3_scale(ghost_soil_accel(c, sown, sbar, p->rho[i], dv, nrm, &A), p->m[i]);
                    fgn = fmax(v3_dot(fg, nrm), 0.0);
                    /* L_ab += sum_g V_g (v_g - v_i)_a (grad_i W_ig)_b with the ghosts' normal
                     * velocity the wall's (free slip: their tangential velocity the particle's),
                     * v_g - v_i = -(u_rel.n) n, grad_i W_ig = -F r_g: (u_rel.n) n_a A_b */
                    const double un = v3_dot(urel, nrm), na[3] = {nrm.x, nrm.y, nrm.z}, ab[3] = {A.x, A.y, A.z};
                    for (int a = 0; a < 3; a++)
                        for (int bb = 0; bb < 3; bb++)
                            lw[a * 3 + bb] += un * na[a] * ab[bb];
                }
                const double fn_tot = (delta > 0.0 ? kn * delta : 0.0) + fgn;
                if (soil && fn_tot > 0.0) {
                    ft = coupling_soil_tangential(c, p->id[i], b, nrm, urel, fn_tot, kn, dt, hist_d[nh]);
                    hist_b[nh++] = b;
                }
                vec3 f = v3_add(v3_add(fn, ft), fg);
                gd[ns] = -1.0;
                if (c->pressure == LAHAR_SPH_WALL_PRESSURE_GHOST && !cross && p->phase[i] == 0) { /* water only: soil has eq. 22-27 */
                    double drw;
                    if (pbar != pbar)
                        pbar = ghost_pbar(c, p, i);
                    f = v3_axpy(p->m[i], ghost_wall_accel(c, p->p[i], pbar, p->rho[i], dv, nrm, urel, &drw), f);
                    drho_g += drw;
                    gn[ns] = nrm;
                    gd[ns] = dv;
                    gu[ns] = urel;
                }
                ftot = v3_add(ftot, f);
                int64_t k = i * SPH_COUPLING_MAX_PER_PARTICLE + ns;
                c->slot_body[k] = cross ? -(b + 1) : b;
                sph_contact *ct = &c->slot[k];
                v3_store(xs, ct->xs);
                v3_store(v3_neg(f), ct->force); /* eq. 20 */
                ct->delta = delta;
                ct->particle_id = p->id[i];
                ns++;
            }
        }
        /* ghost pressure at a concave corner of perpendicular bodies: the quadrant behind both
         * once, not twice (sph_coupling.h) */
        for (int s1 = 0; s1 < ns; s1++)
            for (int s2 = 0; s2 < ns; s2++) {
                if (s1 == s2 || gd[s1] < 0.0 || gd[s2] < 0.0 || fabs(v3_dot(gn[s1], gn[s2])) >= 0.1)
                    continue;
                double drc;
                vec3 fc = v3_scale(ghost_corner_accel(c, p->p[i], pbar, p->rho[i], gd[s1], gn[s1], gd[s2], gn[s2], gu[s1], gu[s2], &drc),
                                   -p->m[i]);
                drho_g -= drc;
                /* eq. 20: wall s1 takes the reaction of the correction; of the half quadrant its
                 * layers keep, the push along n_s2 is wall s2's (a ghost behind both walls pushes
                 * across each wall's own plane), so that part of the reaction (-fc) moves over */
                sph_contact *ca = &c->slot[i * SPH_COUPLING_MAX_PER_PARTICLE + s1];
                sph_contact *cb = &c->slot[i * SPH_COUPLING_MAX_PER_PARTICLE + s2];
                vec3 fb = v3_scale(gn[s2], v3_dot(fc, gn[s2]));
                v3_store(v3_sub(v3_load(ca->force), v3_add(fc, fb)), ca->force);
                v3_store(v3_add(v3_load(cb->force), fb), cb->force);
                ftot = v3_add(ftot, fc);
            }
        c->slot_n[i] = ns;
        if (c->soil_lw_on) {
            c->soil_lw_on[i] = (unsigned char)have_sbar;
            if (have_sbar)
                memcpy(c->soil_lw[i], lw, sizeof lw);
        }
        if (soil) { /* the springs of the pairs in contact now; the others are released */
            const int64_t base = p->id[i] * SPH_COUPLING_MAX_PER_PARTICLE;
            for (int s = 0; s < SPH_COUPLING_MAX_PER_PARTICLE; s++) {
                c->soil_hist_body[base + s] = s < nh ? hist_b[s] : -1;
                if (s < nh)
                    memcpy(c->soil_hist_d[base + s], hist_d[s], sizeof hist_d[s]);
            }
        }
        if (ns == 0 && drho_g == 0.0) /* far from every body (most particles): nothing to add */
            continue;
        double inv_m = 1.0 / p->m[i];
        p->drho[i] += drho_g;
        p->ax[i] += ftot.x * inv_m;
        p->ay[i] += ftot.y * inv_m;
        p->az[i] += ftot.z * inv_m;
    }

    /* serial, in particle order: per-body resultants, contact list, crossings */
    for (int b = 0; b < c->nbody; b++) {
        c->force[b][0] = c->force[b][1] = c->force[b][2] = 0.0;
        c->torque[b][0] = c->torque[b][1] = c->torque[b][2] = 0.0;
        c->body_fill[b] = 0;
    }
    int64_t total = 0;
    c->crossings = 0;
    c->cross_body = -1;
    c->cross_particle_id = -1;
    c->cross_depth = 0.0;
    for (int64_t i = 0; i < n; i++)
        for (int s = 0; s < c->slot_n[i]; s++) {
            int64_t k = i * SPH_COUPLING_MAX_PER_PARTICLE + s;
            int b = c->slot_body[k];
            if (b < 0) {
                b = -b - 1;
                c->slot_body[k] = b;
                if (c->crossings++ == 0) {
                    c->cross_body = b;
                    c->cross_particle_id = c->slot[k].particle_id;
                    c->cross_depth = c->slot[k].delta - c->eps; /* -d: depth inside the surface */
                }
            }
            c->body_fill[b]++;
            total++;
        }
    if (total > c->contacts_cap) {
        int64_t cap = c->contacts_cap;
        while (cap < total)
            cap *= 2;
        sph_contact *nc = realloc(c->contacts, (size_t)cap * sizeof *nc);
        if (!nc)
            return -1;
        c->contacts = nc;
        c->contacts_cap = cap;
    }
    c->body_start[0] = 0;
    for (int b = 0; b < c->nbody; b++) {
        c->body_start[b + 1] = c->body_start[b] + c->body_fill[b];
        c->body_fill[b] = c->body_start[b];
    }
    for (int64_t i = 0; i < n; i++)
        for (int s = 0; s < c->slot_n[i]; s++) {
            int64_t k = i * SPH_COUPLING_MAX_PER_PARTICLE + s;
            int b = c->slot_body[k];
            const sph_contact *ct = &c->slot[k];
            c->contacts[c->body_fill[b]++] = *ct;
            const double *bx = states && c->bodies[b].motion != LAHAR_MOTION_FIXED ? states[b].x : c->bodies[b].x;
            vec3 f = v3_load(ct->force), r = v3_sub(v3_load(ct->xs), v3_load(bx));
            vec3 t = v3_cross(r, f); /* eq. 21 with the torque as r x F */
            for (int a = 0; a < 3; a++) {
                c->force[b][a] += v3_get(f, a);
                c->torque[b][a] += v3_get(t, a);
            }
        }
    c->ncontacts = total;
    return c->crossings;
}
