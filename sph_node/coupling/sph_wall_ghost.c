/* The ghost wall model of the coupling (sph_coupling.h, case keys sph.wall_pressure: ghost and
 * sph.soil_wall_stress: ghost; Adami, Hu & Adams 2012): the kernel sums of the ghost layers behind a
 * body's surface, tabulated once per case, and the accelerations and continuity rates they give a
 * particle near a wall, an edge or a curved surface. sph_coupling_apply calls them per contact. */
#include "sph_coupling.h"
#include "soa_alloc.h"
#include "sph_wall_ghost.h"
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "geometry.h"
#include "vec.h"

/* G(d) = sum over ghost layers at depths s_k = (k + 1/2) dx behind the surface of
 * (1 + s_k/d) dx int_layer W'(r)/r r^2/(r^2 + eta^2) dA, for a particle at distance d in front of it.
 * The layers mirror the fluid lattice (first fluid row at dx/2 in front of the surface, first
 * ghost layer at dx/2 behind it), so for a linear velocity field the fluid rows and the ghosts
 * cancel like a full lattice does; a continuous half-space integral instead leaves 4 % of the wall
 * shear as a spurious force dipole on the first two rows (cubic, h = 1.3 dx). Within a layer the
 * integral is continuous (midpoint rule), since the fluid slides along the wall. */
double sph_ghost_layers(const kernel *k, int dim, double d, double dx)
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
double sph_ghost_layers_curved(const kernel *k, int dim, double d, double dx, double R)
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
        c->soil_lw = lahar_soa_calloc((size_t)c->pcap, sizeof *c->soil_lw);
    if (!c->soil_lw_on)
        c->soil_lw_on = lahar_soa_calloc((size_t)c->pcap, 1);
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
vec3 sph_ghost_wall_accel(const sph_coupling *c, double p, double pbar, double rho, double d, vec3 n, vec3 u,
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
double sph_ghost_pbar(const sph_coupling *c, const sph_particles *p, int64_t i)
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
void sph_ghost_soil_sigbar(const sph_coupling *c, const sph_particles *p, int64_t i, double out[SPH_NSTRESS])
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
vec3 sph_ghost_soil_accel(const sph_coupling *c, const double si[SPH_NSTRESS], const double sbar[SPH_NSTRESS],
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
vec3 sph_ghost_corner_accel(const sph_coupling *c, double p, double pbar, double rho, double da, vec3 na,
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
