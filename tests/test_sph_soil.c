/* SPH soil (sph_node/soil/sph_soil.h) against closed forms:
 *  1. return mapping (Bui 2008 section 3.3): a stress beyond the Drucker-Prager surface is scaled
 *     back onto it (|f| < 1e-12 of the stress scale) with I1 and the direction of s kept; a
 *     tensile stress of a cohesionless soil goes to zero; with cohesion to the apex
 *     I1 = k_c / alpha_phi; a stress inside is left bitwise alone. The plane-strain constants
 *     equal tan(phi)/sqrt(9 + 12 tan^2 phi) and 3c/sqrt(9 + 12 tan^2 phi) (30 deg: 0.160128, 0.832050 c).
 *  2. elastic stress rate of a uniform velocity gradient (2D lattice, quintic kernel, interior
 *     particle): dsigma = 2G e + K tr(eps) I, the plane-strain dsigma_zz = (K - 2G/3) tr(eps) too,
 *     within 1 % of |dsigma| (the lattice gradient sum of the kernel, ~0.3 %);
 *  3. Jaumann rate of a rigid rotation v = w x (-y, x) of a pre-stressed soil (sigma_xx = -s0):
 *     dsigma = W sigma - sigma W, dsigma_xy = -s0 w, no elastic part, within 1 %;
 *  4. a uniform stress exerts no force on an interior particle: |a - g| < 1e-9 s0/(rho dx);
 *  5. a water-only fluid allocates no stress arrays;
 *  6. seepage (Trujillo-Vela et al. 2020, eq. 8-10): water moving at u through a resting soil on the same periodic
 *     lattice: the water's acceleration is -(g/k_h) u (sum_s V_s W = 1) within 1 %, and the
 *     water-soil forces cancel pair by pair: |sum_i m_i (a_i - b_i)| < 1e-12 of sum_water m |a - b|;
 *  7. soil-DEM friction (Trujillo-Vela et al. 2020, eq. 22-27) of soil particles sliding on a fixed plate: after one
 *     evaluation F_t = -K_n dt u_tau (to 1e-12), the body takes -F; after enough evaluations the
 *     spring is capped, |F_t| = mu_phi |F_n|; the spring follows its particle id through a sort that
 *     swaps the particles; leaving the halo releases it (a new contact starts from dt u again).
 *  8. pass 2 over pass 1's neighbour list (sph_soil.nb_j) gives the same bits as the cell walk
 *     (the fallback of a particle whose list overflowed), with stresses in tension at some
 *     particles so the artificial stress takes part.
 *  9. the soil ghosts' share of the velocity gradient (sph.soil_wall_stress: ghost): a floor-row
 *     particle moving alone off the floor has L_yy = 0 within 5 % of its neighbours' share (the
 *     one-sided compression that made a collapsing column blow up); a field v_y = G y vanishing on
 *     the floor reads L_yy within 30 % of G in the floor row (0.73 G: the ghosts move with the wall,
 *     they do not extrapolate the field; 0.51 G without them). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "shape_build.h"
#include "case_keys.h"
#include "sph_fluid.h"
#include "sph_soil_model.h"

#include "test_util.h"

static const double DX = 0.01, RHO = 2000.0, PI = 3.14159265358979323846;

static sph_soil_material sand(double phi_deg, double c)
{
    return (sph_soil_material){.density = RHO, .young = 1e6, .poisson = 0.3, .phi = phi_deg * PI / 180.0,
                               .cohesion = c, .psi = 0.0, .mu_phi = 0.5, .av_alpha = 0.1, .gravity = {0.0, -9.81, 0.0}};
}

static double yield_f(const sph_soil *s, const double sig[6])
{
    double i1 = sig[0] + sig[3] + sig[5], m = i1 / 3.0;
    double a = sig[0] - m, b = sig[3] - m, c = sig[5] - m;
    double j2 = 0.5 * (a * a + b * b + c * c) + sig[1] * sig[1] + sig[2] * sig[2] + sig[4] * sig[4];
    return s->alpha_phi * i1 + sqrt(j2) - s->kc;
}

static void test_return(void)
{
    sph_soil s;
    memset(&s, 0, sizeof s);
    s.mat = sand(30.0, 100.0);
    s.model = sph_soil_model_find("drucker_prager"); /* what sph_soil_init picks for this material */
    sph_soil_constants(&s.mat, &s.G, &s.K, &s.cs, &s.alpha_phi, &s.kc, &s.alpha_psi);
    CHECK(fabs(s.alpha_phi - 0.1601281538) < 1e-9 && fabs(s.kc - 83.20502943) < 1e-6,
          "plane-strain constants alpha_phi %.10f k_c %.8f", s.alpha_phi, s.kc);
    double sig[6] = {-1000.0, 600.0, 0.0, -1000.0, 0.0, -1000.0}; /* sqrt(J2) = 600 > 0.16 * 3000 + 83 */
    double before[6];
    memcpy(before, sig, sizeof sig);
    CHECK(yield_f(&s, sig) > 0.0, "start outside the surface");
    sph_soil_return(&s, sig);
    CHECK(fabs(yield_f(&s, sig)) < 1e-12 * 1000.0, "on the surface after the return: f = %g", yield_f(&s, sig));
    CHECK(fabs(sig[0] + sig[3] + sig[5] + 3000.0) < 1e-9, "I1 kept");
    CHECK(sig[1] > 0.0 && fabs(sig[0] - sig[3]) < 1e-9 && sig[2] == 0.0 && sig[4] == 0.0, "direction of s kept");
    double inside[6] = {-1000.0, 100.0, 0.0, -900.0, 0.0, -950.0}, keep[6];
    memcpy(keep, inside, sizeof keep);
    sph_soil_return(&s, inside);
    CHECK(memcmp(inside, keep, sizeof keep) == 0, "a stress inside the surface is left alone");
    /* tension: to the apex */
    double ten[6] = {500.0, 50.0, 0.0, 200.0, 0.0, 100.0};
    sph_soil_return(&s, ten);
    double apex = s.kc / s.alpha_phi;
    CHECK(fabs(ten[0] + ten[3] + ten[5] - apex) < 1e-9 * apex && fabs(yield_f(&s, ten)) < 1e-9 * apex,
          "tension with cohesion goes to the apex I1 = %g (got I1 %g, f %g)", apex, ten[0] + ten[3] + ten[5],
          yield_f(&s, ten));
    s.mat = sand(30.0, 0.0);
    sph_soil_constants(&s.mat, &s.G, &s.K, &s.cs, &s.alpha_phi, &s.kc, &s.alpha_psi);
    double ten0[6] = {500.0, 50.0, 0.0, 200.0, 0.0, 100.0};
    sph_soil_return(&s, ten0);
    double mx = 0.0;
    for (int a = 0; a < 6; a++)
        mx = fmax(mx, fabs(ten0[a]));
    CHECK(mx < 1e-9, "tension of a cohesionless soil vanishes (max |sigma| %g)", mx);
    (void)before;
}

/* A 2D soil lattice of n x n particles, velocity v(x) = L x about the centre, stress sig0 on every
 * particle; rates evaluated; returns the index of the centre particle. */
static int64_t soil_lattice(sph_fluid *f, int n, const double L[2][2], const double sig0[6])
{
    sph_params prm;
    sph_params_default(&prm);
    prm.opt.mu = 0.0;
    prm.opt.delta = 0.0;
    prm.dim = 2;
    snprintf(prm.opt.kernel, sizeof prm.opt.kernel, "%s", "quintic");
    prm.opt.h_over_dx = 1.0;
    prm.dx = DX;
    prm.rho0 = 1000.0;
    prm.opt.c0 = 10.0;
    prm.body_force[1] = -9.81;
    prm.soil = 1;
    prm.soil_mat = sand(30.0, 0.0);
    char err[256];
    if (sph_fluid_init(f, &prm, (int64_t)n * n, err, sizeof err) != 0) {
        CHECK(0, "init: %s", err);
        return -1;
    }
    double c = 0.5 * n * DX;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double x[3] = {(i + 0.5) * DX, (j + 0.5) * DX, 0.0};
            double rx = x[0] - c, ry = x[1] - c;
            double v[3] = {L[0][0] * rx + L[0][1] * ry, L[1][0] * rx + L[1][1] * ry, 0.0};
            sph_particles_add(&f->p, x, v, RHO * DX * DX, RHO, SPH_SOIL_PHASE);
        }
    int64_t centre_id = (int64_t)(n / 2) * n + n / 2;
    sph_cells_sort(&f->cells, &f->p);
    for (int64_t i = 0; i < f->p.n; i++)
        for (int a = 0; a < 6; a++)
            f->p.sig[a][i] = sig0[a];
    sph_fluid_rates(f, NULL, 1e-5);
    for (int64_t i = 0; i < f->p.n; i++)
        if (f->p.id[i] == centre_id)
            return i;
    return -1;
}

static void test_elastic_rate(void)
{
    const double L[2][2] = {{1e-3, 4e-4}, {-2e-4, -3e-4}}, zero[6] = {0};
    sph_fluid f;
    int64_t i = soil_lattice(&f, 13, L, zero);
    if (i < 0) {
        sph_fluid_free(&f);
        return;
    }
    const sph_soil *s = &f.soil;
    double exx = L[0][0], eyy = L[1][1], exy = 0.5 * (L[0][1] + L[1][0]), tr = exx + eyy;
    double ref[6] = {2 * s->G * (exx - tr / 3) + s->K * tr, 2 * s->G * exy, 0.0, 2 * s->G * (eyy - tr / 3) + s->K * tr,
                     0.0, (s->K - 2.0 / 3.0 * s->G) * tr};
    double scale = 0.0, err = 0.0;
    for (int a = 0; a < 6; a++) {
        scale = fmax(scale, fabs(ref[a]));
        err = fmax(err, fabs(s->dsig[a][i] - ref[a]));
    }
    CHECK(err < 0.01 * scale, "elastic stress rate: max error %g of %g (xx %g vs %g, xy %g vs %g, zz %g vs %g)", err,
          scale, s->dsig[0][i], ref[0], s->dsig[1][i], ref[1], s->dsig[5][i], ref[5]);
    printf("elastic stress rate: max error %.3g %% of |dsigma|\n", 100.0 * err / scale);
    sph_fluid_free(&f);
}

static void test_jaumann_and_uniform(void)
{
    const double w = 0.01, s0 = 1000.0;
    const double L[2][2] = {{0.0, -w}, {w, 0.0}}; /* v = w (-y, x) */
    const double sig0[6] = {-s0, 0.0, 0.0, 0.0, 0.0, 0.0};
    sph_fluid f;
    int64_t i = soil_lattice(&f, 13, L, sig0);
    if (i < 0) {
        sph_fluid_free(&f);
        return;
    }
    const sph_soil *s = &f.soil;
    double ref_xy = -s0 * w;
    CHECK(fabs(s->dsig[1][i] - ref_xy) < 0.01 * fabs(ref_xy) && fabs(s->dsig[0][i]) < 0.01 * fabs(ref_xy) &&
              fabs(s->dsig[3][i]) < 0.01 * fabs(ref_xy),
          "Jaumann rate of a rigid rotation: xy %g (ref %g), xx %g, yy %g", s->dsig[1][i], ref_xy, s->dsig[0][i],
          s->dsig[3][i]);
    printf("Jaumann: dsigma_xy %.6g vs %.6g\n", s->dsig[1][i], ref_xy);
    /* 4. uniform stress: no net force on the interior particle (a rigid rotation adds no
     * artificial viscosity: v_ij . x_ij = 0) */
    double da = hypot(f.p.ax[i] - 0.0, f.p.ay[i] + 9.81);
    CHECK(da < 1e-9 * s0 / (RHO * DX), "uniform stress: |a - g| = %g", da);
    sph_fluid_free(&f);
}

static void test_water_only(void)
{
    sph_params prm;
    sph_params_default(&prm);
    prm.opt.mu = 0.0;
    prm.opt.delta = 0.0;
    prm.dim = 2;
    prm.dx = DX;
    prm.rho0 = 1000.0;
    prm.opt.c0 = 10.0;
    sph_fluid f;
    char err[256];
    CHECK(sph_fluid_init(&f, &prm, 100, err, sizeof err) == 0, "init");
    CHECK(f.p.sig[0] == NULL && !f.has_soil, "a water-only fluid has no stress arrays");
    sph_fluid_free(&f);
}

static void test_seepage(void)
{
    const int n = 10;
    const double kh = 0.01, g = 9.81, u = 2e-3;
    sph_params prm;
    sph_params_default(&prm);
    prm.opt.mu = 0.0;
    prm.opt.delta = 0.0;
    prm.dim = 2;
    prm.dx = DX;
    prm.rho0 = 1000.0;
    prm.opt.c0 = 10.0;
    prm.opt.periodic[0] = prm.opt.periodic[1] = 1;
    prm.opt.hi[0] = prm.opt.hi[1] = n * DX;
    prm.soil = 1;
    prm.soil_mat = sand(30.0, 1e4);
    prm.soil_mat.kh = kh;
    prm.soil_mat.g_ref = g;
    prm.soil_mat.rho_water = 1000.0;
    prm.soil_mat.gravity[1] = 0.0;
    sph_fluid f;
    char err[256];
    if (sph_fluid_init(&f, &prm, 2 * n * n, err, sizeof err) != 0) {
        CHECK(0, "init: %s", err);
        return;
    }
    for (int ph = 0; ph < 2; ph++)
        for (int i = 0; i < n; i++)
            for (int j = 0; j < n; j++) {
                double x[3] = {(i + 0.5) * DX, (j + 0.5) * DX, 0.0}, v[3] = {ph == 0 ? u : 0.0, 0.0, 0.0};
                double rho = ph == 0 ? 1000.0 : RHO;
                sph_particles_add(&f.p, x, v, rho * DX * DX, rho, ph == 0 ? 0 : SPH_SOIL_PHASE);
            }
    sph_cells_sort(&f.cells, &f.p);
    sph_fluid_rates(&f, NULL, 1e-5);
    double ref = -g / kh * u, worst = 0.0, mom[2] = {0.0, 0.0}, scale = 0.0;
    for (int64_t i = 0; i < f.p.n; i++) {
        mom[0] += f.p.m[i] * f.p.ax[i];
        mom[1] += f.p.m[i] * f.p.ay[i];
        if (f.p.phase[i] == 0) {
            worst = fmax(worst, fabs(f.p.ax[i] - ref) / fabs(ref));
            scale += f.p.m[i] * fabs(f.p.ax[i]);
        }
    }
    CHECK(worst < 0.01, "water seepage acceleration: worst relative error %g (reference %g m/s^2)", worst, ref);
    CHECK(hypot(mom[0], mom[1]) < 1e-12 * scale, "water-soil forces cancel: |sum m a| = %g of %g",
          hypot(mom[0], mom[1]), scale);
    printf("seepage: water acceleration within %.3g %% of -(g/k_h) u; net force %.3g of %.3g\n", 100.0 * worst,
           hypot(mom[0], mom[1]), scale);
    sph_fluid_free(&f);
}

/* Particle id's tangential force (x) after an evaluation of the coupling alone. */
static double friction_x(sph_fluid *f, int64_t id, double dt)
{
    for (int64_t i = 0; i < f->p.n; i++)
        f->p.ax[i] = f->p.ay[i] = f->p.az[i] = 0.0;
    sph_coupling_apply(&f->cpl, &f->p, NULL, dt);
    for (int64_t i = 0; i < f->p.n; i++)
        if (f->p.id[i] == id)
            return f->p.ax[i] * f->p.m[i];
    return NAN;
}

static void test_friction(void)
{
    const double dt = 1e-4, mu = 0.5, uA = 0.2, uB = -0.1;
    lahar_body plate;
    memset(&plate, 0, sizeof plate);
    double half[2] = {1.0, 0.02}, t[3] = {0.0, -0.03, 0.0}; /* swept top surface at y = 0 */
    lahar_shape_make_box2d(&plate.shape, half, 0.01);
    lahar_shape_transform(&plate.shape, NULL, t, 1.0);
    plate.motion = LAHAR_MOTION_FIXED;
    plate.convex = 1;
    plate.q[0] = 1.0;
    sph_params prm;
    sph_params_default(&prm);
    prm.opt.mu = 0.0;
    prm.opt.delta = 0.0;
    prm.dim = 2;
    prm.dx = DX;
    prm.rho0 = 1000.0;
    prm.opt.c0 = 10.0;
    prm.soil = 1;
    prm.soil_mat = sand(30.0, 0.0);
    prm.soil_mat.mu_phi = mu;
    sph_fluid f;
    char err[256];
    if (sph_fluid_init(&f, &prm, 2, err, sizeof err) != 0) {
        CHECK(0, "init: %s", err);
        lahar_shape_free(&plate.shape);
        return;
    }
    const double eps = 0.5 * DX, depth = 0.2 * eps, m = RHO * DX * DX;
    double xa[3] = {0.5, eps - depth, 0.0}, va[3] = {uA, 0.0, 0.0}; /* id 0, right */
    double xb[3] = {0.0, eps - depth, 0.0}, vb[3] = {uB, 0.0, 0.0}; /* id 1, left */
    sph_particles_add(&f.p, xa, va, m, RHO, SPH_SOIL_PHASE);
    sph_particles_add(&f.p, xb, vb, m, RHO, SPH_SOIL_PHASE);
    sph_fluid_attach_bodies(&f, 1, &plate);
    const double kn = 0.1 * m / (dt * dt), fn = kn * depth;
    double fa = friction_x(&f, 0, dt);
    CHECK(fabs(fa + kn * dt * uA) < 1e-12 * kn * dt * uA, "first step: F_t %.12g vs -K_n dt u = %.12g", fa,
          -kn * dt * uA);
    CHECK(fabs(f.cpl.force[0][0] - kn * dt * (uA + uB)) < 1e-9 * kn * dt * uA, "the plate takes -F_t: %g vs %g",
          f.cpl.force[0][0], kn * dt * (uA + uB));
    CHECK(fabs(f.cpl.force[0][1] + 2.0 * fn) < 1e-9 * fn, "and -F_n: %g vs %g", f.cpl.force[0][1], -2.0 * fn);
    int64_t before = f.p.id[0];
    sph_cells_sort(&f.cells, &f.p); /* B (left) comes first now */
    CHECK(f.p.id[0] != before, "the sort swaps the two particles (test premise)");
    double fb = friction_x(&f, 1, dt);
    fa = 0.0;
    for (int64_t i = 0; i < f.p.n; i++)
        if (f.p.id[i] == 0)
            fa = f.p.ax[i] * f.p.m[i];
    CHECK(fabs(fa + 2.0 * kn * dt * uA) < 1e-9 * kn * dt * uA && fabs(fb + 2.0 * kn * dt * uB) < 1e-9 * kn * dt * fabs(uB),
          "the springs follow their ids through the sort: %g vs %g, %g vs %g", fa, -2.0 * kn * dt * uA, fb,
          -2.0 * kn * dt * uB);
    for (int s = 0; s < 200; s++) /* slip: the spring is capped at mu F_n / K_n */
        fa = friction_x(&f, 0, dt);
    CHECK(fabs(fabs(fa) - mu * fn) < 1e-12 * mu * fn && fa < 0.0, "capped: |F_t| %.12g vs mu F_n %.12g", fabs(fa),
          mu * fn);
    for (int64_t i = 0; i < f.p.n; i++) /* out of the halo: released */
        f.p.y[i] = eps + 0.5 * eps;
    friction_x(&f, 0, dt);
    for (int64_t i = 0; i < f.p.n; i++)
        f.p.y[i] = eps - depth;
    fa = friction_x(&f, 0, dt);
    CHECK(fabs(fa + kn * dt * uA) < 1e-9 * kn * dt * uA, "released on leaving the halo: F_t %g vs %g", fa,
          -kn * dt * uA);
    printf("friction: first step, sort, cap at mu F_n = %.6g N/m, release: checked\n", mu * fn);
    sph_fluid_free(&f);
    lahar_shape_free(&plate.shape);
}

static void test_list_equals_walk(void)
{
    const double L[2][2] = {{2e-3, 7e-4}, {-5e-4, -1e-3}}, zero[6] = {0};
    sph_fluid f;
    if (soil_lattice(&f, 13, L, zero) < 0) {
        sph_fluid_free(&f);
        return;
    }
    sph_particles *p = &f.p;
    const int64_t n = p->n;
    /* a stress varying from particle to particle, in tension (xx > 0) at every third, and a
     * velocity that is not linear */
    for (int64_t i = 0; i < n; i++) {
        double x = p->x[i], y = p->y[i];
        p->sig[0][i] = (i % 3 == 0 ? 300.0 : -800.0) - 2e4 * y;
        p->sig[1][i] = 150.0 * sin(40.0 * x);
        p->sig[3][i] = -1200.0 - 1e4 * x;
        p->sig[5][i] = -900.0;
        p->vx[i] += 1e-3 * sin(90.0 * y);
        p->vy[i] += 1e-3 * cos(70.0 * x);
    }
    sph_fluid_rates(&f, NULL, 1e-5);
    int64_t listed = 0, tensile = 0;
    for (int64_t i = 0; i < n; i++)
        listed += f.soil.nb_n[i] > 0, tensile += f.soil.tensile[i];
    CHECK(listed == n && tensile > 0, "neighbour list: %lld of %lld particles listed, %lld in tension", (long long)listed,
          (long long)n, (long long)tensile);
    double *ref = malloc((size_t)n * 4 * sizeof(double));
    if (!ref) {
        sph_fluid_free(&f);
        return;
    }
    memcpy(ref, p->ax, (size_t)n * sizeof(double));
    memcpy(ref + n, p->ay, (size_t)n * sizeof(double));
    memcpy(ref + 2 * n, p->az, (size_t)n * sizeof(double));
    memcpy(ref + 3 * n, p->drho, (size_t)n * sizeof(double));
    for (int64_t i = 0; i < n; i++)
        f.soil.nb_n[i] = -1; /* as if every list had overflowed: pass 2 walks the cells */
    int64_t nwater = 0;
    sph_soil_momentum(&f.soil, p, &f.cells, &f.k, &nwater);
    int same = memcmp(ref, p->ax, (size_t)n * sizeof(double)) == 0 &&
               memcmp(ref + n, p->ay, (size_t)n * sizeof(double)) == 0 &&
               memcmp(ref + 2 * n, p->az, (size_t)n * sizeof(double)) == 0 &&
               memcmp(ref + 3 * n, p->drho, (size_t)n * sizeof(double)) == 0;
    CHECK(same, "pass 2 over the neighbour list differs from the cell walk");
    if (same)
        printf("neighbour list: pass 2 bitwise equal to the cell walk (%lld particles, %lld in tension)\n",
           (long long)n, (long long)tensile);
    free(ref);
    sph_fluid_free(&f);
}

/* A soil lattice nx x ny on a fixed plate (swept top surface y = 0, rows at (j + 1/2) dx) with the
 * ghost wall stress, velocity v_y = vel(x, y), zero stress; rates evaluated. Returns the index of
 * the floor-row particle in column nx / 2. */
static int64_t soil_on_plate(sph_fluid *f, lahar_body *plate, int nx, int ny, double (*vel)(double, double))
{
    memset(plate, 0, sizeof *plate);
    double half[2] = {1.0, 0.02}, t[3] = {0.5 * nx * DX, -0.03, 0.0};
    lahar_shape_make_box2d(&plate->shape, half, 0.01);
    lahar_shape_transform(&plate->shape, NULL, t, 1.0);
    plate->motion = LAHAR_MOTION_FIXED;
    plate->convex = 1;
    plate->q[0] = 1.0;
    sph_params prm;
    sph_params_default(&prm);
    prm.opt.mu = 0.0;
    prm.opt.delta = 0.0;
    prm.dim = 2;
    prm.dx = DX;
    prm.rho0 = 1000.0;
    prm.opt.c0 = 10.0;
    prm.soil = 1;
    prm.soil_mat = sand(30.0, 0.0);
    prm.opt.soil_wall_stress = LAHAR_SPH_WALL_PRESSURE_GHOST;
    char err[256];
    if (sph_fluid_init(f, &prm, (int64_t)nx * ny, err, sizeof err) != 0) {
        CHECK(0, "init: %s", err);
        return -1;
    }
    for (int i = 0; i < nx; i++)
        for (int j = 0; j < ny; j++) {
            double x[3] = {(i + 0.5) * DX, (j + 0.5) * DX, 0.0}, v[3] = {0.0, vel(x[0], x[1]), 0.0};
            sph_particles_add(&f->p, x, v, RHO * DX * DX, RHO, SPH_SOIL_PHASE);
        }
    if (sph_fluid_attach_bodies(f, 1, plate) != 0) {
        CHECK(0, "attach the plate");
        return -1;
    }
    sph_cells_sort(&f->cells, &f->p);
    sph_fluid_rates(f, NULL, 1e-5);
    const int64_t id = (int64_t)(nx / 2) * ny; /* column nx / 2, row 0 */
    for (int64_t i = 0; i < f->p.n; i++)
        if (f->p.id[i] == id)
            return i;
    return -1;
}

static double vel_lin(double x, double y) /* G y with G = 1/s, zero on the floor */
{
    (void)x;
    return y;
}
static const double U_ALONE = 0.01;
static double vel_alone(double x, double y)
{
    return fabs(x - 5.5 * DX) < 0.1 * DX && y < DX ? U_ALONE : 0.0;
}

/* 9. the soil ghosts' share of the velocity gradient (sph_coupling_set_soil_wall): a floor-row
 * particle moving alone away from the floor, its neighbours and the floor at rest, is a particle
 * displaced, not a strain: with the ghosts standing still with the floor its L_yy is 0 (its
 * neighbours alone give -0.4 u/dx: the compression that, growing its own stress, pushed it further
 * off the floor, the blow-up of a collapsing column). Measured through the elastic stress rate
 * (zero stress: dsigma_yy = (K + 4G/3) L_yy). */
static void test_wall_gradient(void)
{
    sph_fluid f;
    lahar_body plate;
    int64_t i = soil_on_plate(&f, &plate, 11, 6, vel_alone);
    if (i >= 0) {
        const sph_soil *s = &f.soil;
        double lyy = s->dsig[3][i] / (s->K + 4.0 / 3.0 * s->G), lyy_nb = s->grad[4][i];
        CHECK(f.cpl.soil_lw_on[i], "the floor-row particle has ghosts");
        CHECK(lyy_nb < -0.2 * U_ALONE / DX, "premise: the neighbours alone see a compression (L_yy %g 1/s)", lyy_nb);
        CHECK(fabs(lyy) < 0.05 * fabs(lyy_nb), "lone particle off the floor: L_yy %g 1/s with the ghosts, %g without",
              lyy, lyy_nb);
        printf("wall gradient: lone particle L_yy %.3g 1/s with the ghosts, %.3g without (u/dx = %g)\n", lyy, lyy_nb,
               U_ALONE / DX);
    }
    sph_fluid_free(&f);
    lahar_shape_free(&plate.shape);
    i = soil_on_plate(&f, &plate, 11, 6, vel_lin);
    if (i >= 0) {
        const sph_soil *s = &f.soil;
        double lyy = s->dsig[3][i] / (s->K + 4.0 / 3.0 * s->G), lyy_nb = s->grad[4][i];
        CHECK(fabs(lyy - 1.0) < 0.3 && lyy > lyy_nb, "v_y = G y (G = 1/s) on the floor row: L_yy %g with the ghosts, %g without",
              lyy, lyy_nb);
        printf("wall gradient: v_y = G y, floor row L_yy %.3g G with the ghosts, %.3g G without\n", lyy, lyy_nb);
    }
    sph_fluid_free(&f);
    lahar_shape_free(&plate.shape);
}

/* The constitutive models the case can name (materials.NAME.constitutive, common/io/case_keys.c)
 * are the SPH node's (sph_soil_models.c), and a material without one is Drucker-Prager: the
 * loader's index and the node's lookup agree, and sph_soil_init picks the same functions. */
static void test_models(void)
{
    const lahar_key *k = lahar_key_find(lahar_key_section_find("materials.NAME"), "constitutive");
    CHECK(k && k->choices && k->choices[0], "materials.NAME.constitutive: no choices in the key table");
    for (int i = 0; k && k->choices && k->choices[i]; i++)
        CHECK(sph_soil_model_find(k->choices[i]) != NULL, "constitutive model '%s' of the key table is not in "
              "sph_soil_models.c", k->choices[i]);
    CHECK(sph_soil_model_find("no_such_model") == NULL, "an unknown model name was found");
    const sph_soil_model *dp = sph_soil_model_find("drucker_prager");
    CHECK(dp && !strcmp(k ? k->def : "", "drucker_prager"), "the default model is not drucker_prager");
}

int main(void)
{
    test_models();
    test_return();
    test_elastic_rate();
    test_jaumann_and_uniform();
    test_water_only();
    test_seepage();
    test_friction();
    test_list_equals_walk();
    test_wall_gradient();
    if (failures)
        fprintf(stderr, "%d check(s) failed\n", failures);
    return failures != 0;
}
