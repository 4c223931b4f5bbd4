/* SPS (Smagorinsky) turbulence of the SPH core (sph_fluid.h; Canelas et al. 2015 eq. 10-11, Dalrymple &
 * Rogers 2006), checked against analytic values:
 *  1. uniform shear u = gamma y on a lattice, periodic in x (and z in 3D): in the interior (two
 *     kernel supports away from the top and bottom rows) nu_t = (C_s dx)^2 gamma within 1 %
 *     (quintic 2D/3D, cubic 3D; cubic 2D at h = 1.3 dx is 1.05 % off because its lattice
 *     gradient sum G is, so there nu_t = (C_s dx)^2 gamma G to 1e-12 is asserted), and the SPS
 *     force of this constant stress (its divergence) vanishes to round-off: |a - g| < 1e-9 of the
 *     scale |tau| / (rho dx) of one pair's term.
 *  2. a shear wave u = A sin(k y) (periodic in x and y): the SPS acceleration equals the analytic
 *     divergence of tau (Canelas et al. 2015, eq. 11 with nu_t = (C_s dx)^2 |u'|):
 *       a_x = d/dy (nu_t u') = -2 (C_s dx)^2 A^2 k^3 sin(ky) |cos(ky)|,
 *       a_y = d/dy (-2/3 C_I dx^2 u'^2) = 4/3 C_I dx^2 A^2 k^3 sin(ky) cos(ky),
 *     RMS error within 3 % of the amplitude of a_x (40 particles per wavelength);
 *  3. stability: a 2D dam break (column 0.2 x 0.4 m in a 0.8 m tank of fixed walls) with SPS on
 *     runs 400 steps: no particle crosses a wall, all states finite, |v|max below sqrt(2 g H)
 *     (free fall from the column top) + 10 %, density within 5 % of rho0 everywhere. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "shape_build.h"
#include "sph_fluid.h"

#include "test_bodies.h"
#include "test_util.h"

static const double DX = 0.01, RHO0 = 1000.0, CS = 0.12;

static void shear_params(sph_params *prm, int dim)
{
    sph_params_default(prm);
    prm->opt.mu = 0.0;
    prm->opt.delta = 0.0;
    prm->dim = dim;
    prm->dx = DX;
    prm->rho0 = RHO0;
    prm->opt.c0 = 10.0;
    prm->opt.sps = 1;
    prm->opt.sps_cs = CS;
}

/* The SPH velocity gradient on an unbounded lattice: dv_x/dy = gamma G with
 * G = -sum_j V_j F(r_j) y_j^2 over the lattice offsets (1 for an exact kernel sum). */
static double lattice_gradient_sum(const kernel *k, int dim)
{
    const int R = 6;
    double G = 0.0, vol = pow(DX, dim);
    for (int a = -R; a <= R; a++)
        for (int b = -R; b <= R; b++)
            for (int c = dim == 3 ? -R : 0; c <= (dim == 3 ? R : 0); c++) {
                double r = DX * sqrt((double)(a * a + b * b + c * c));
                if (r > 0.0)
                    G -= vol * kernel_dwdr(k, r) / r * (b * DX) * (b * DX);
            }
    return G;
}

/* 1. linear shear in dim 2 or 3 with kernel `kname` (default h = 1.3 dx). nu_t must equal
 * (C_s dx)^2 gamma G to 1e-12 (G the lattice gradient sum above: this checks the strain rate,
 * |S| and nu_t without the kernel's own discretisation error) and, with exact_bound, also
 * (C_s dx)^2 gamma within 1 %. */
static void check_linear_shear(int dim, const char *kname, int exact_bound)
{
    const int NX = 12, NY = 30, NZ = dim == 3 ? 12 : 1;
    const double gamma = 5.0;
    sph_params prm;
    shear_params(&prm, dim);
    snprintf(prm.opt.kernel, sizeof prm.opt.kernel, "%s", kname);
    prm.opt.periodic[0] = 1;
    prm.opt.hi[0] = NX * DX;
    if (dim == 3) {
        prm.opt.periodic[2] = 1;
        prm.opt.hi[2] = NZ * DX;
    }
    sph_fluid f;
    char err[256];
    if (sph_fluid_init(&f, &prm, (int64_t)NX * NY * NZ, err, sizeof err) != 0) {
        CHECK(0, "%s", err);
        return;
    }
    double lo[3] = {0, 0, 0}, hi[3] = {NX * DX, NY * DX, NZ * DX}, v0[3] = {0, 0, 0};
    sph_particles_add_box(&f.p, dim, DX, RHO0, lo, hi, v0);
    for (int64_t i = 0; i < f.p.n; i++)
        f.p.vx[i] = gamma * f.p.y[i];
    if (sph_cells_sort(&f.cells, &f.p) != 0 || sph_fluid_rates(&f, NULL, 1e-4) < 0) {
        CHECK(0, "rates failed");
        sph_fluid_free(&f);
        return;
    }
    const double nut_exact = CS * DX * CS * DX * gamma;
    /* one pair's SPS term is about m tau/rho^2 |grad W| ~ |tau| / (rho dx) */
    const double scale = (nut_exact * gamma + SPH_SPS_CI * DX * DX * gamma * gamma) / DX;
    const double G = lattice_gradient_sum(&f.k, dim);
    double worst_nut = 0.0, worst_g = 0.0, worst_a = 0.0;
    int interior = 0;
    for (int64_t i = 0; i < f.p.n; i++) {
        double y = f.p.y[i];
        /* the force at i uses tau of neighbours up to one support away, whose gradients need a
         * full support themselves */
        if (y < 2.0 * f.k.support || y > NY * DX - 2.0 * f.k.support)
            continue;
        interior++;
        worst_nut = fmax(worst_nut, fabs(f.sps_nut[i] / nut_exact - 1.0));
        worst_g = fmax(worst_g, fabs(f.sps_nut[i] / (nut_exact * G) - 1.0));
        worst_a = fmax(worst_a, fabs(f.p.ax[i]) + fabs(f.p.ay[i]) + fabs(f.p.az[i]));
    }
    printf("%dD linear shear, %s: %d interior particles, nu_t rel error max %.3e (bound %s), against "
           "(C_s dx)^2 gamma G (G - 1 = %.3e) %.3e (bound 1e-12), |a_SPS| max %.3e = %.3e of the pair scale "
           "(bound 1e-9)\n",
           dim, kname, interior, worst_nut, exact_bound ? "1e-2" : "none", G - 1.0, worst_g, worst_a, worst_a / scale);
    CHECK(interior > 0, "no interior particles");
    CHECK(worst_g < 1e-12, "%dD %s: nu_t off the lattice value by %.3e (relative)", dim, kname, worst_g);
    CHECK(!exact_bound || worst_nut < 1e-2, "%dD %s: nu_t off by %.3e (relative)", dim, kname, worst_nut);
    CHECK(worst_a < 1e-9 * scale, "%dD: SPS force of a constant stress %.3e, scale %.3e", dim, worst_a, scale);
    sph_fluid_free(&f);
}

/* 2. shear wave: the SPS acceleration against the analytic divergence */
static void check_shear_wave(void)
{
    const int NX = 8, NY = 40;
    const double A = 0.2, L = NY * DX, k = 2.0 * M_PI / L;
    sph_params prm;
    shear_params(&prm, 2);
    prm.opt.periodic[0] = prm.opt.periodic[1] = 1;
    prm.opt.hi[0] = NX * DX;
    prm.opt.hi[1] = L;
    sph_fluid f;
    char err[256];
    if (sph_fluid_init(&f, &prm, (int64_t)NX * NY, err, sizeof err) != 0) {
        CHECK(0, "%s", err);
        return;
    }
    double lo[3] = {0, 0, 0}, hi[3] = {NX * DX, L, 0}, v0[3] = {0, 0, 0};
    sph_particles_add_box(&f.p, 2, DX, RHO0, lo, hi, v0);
    for (int64_t i = 0; i < f.p.n; i++)
        f.p.vx[i] = A * sin(k * f.p.y[i]);
    if (sph_cells_sort(&f.cells, &f.p) != 0 || sph_fluid_rates(&f, NULL, 1e-4) < 0) {
        CHECK(0, "rates failed");
        sph_fluid_free(&f);
        return;
    }
    const double c2 = CS * DX * CS * DX, amp = 2.0 * c2 * A * A * k * k * k;
    double ex = 0.0, ey = 0.0;
    for (int64_t i = 0; i < f.p.n; i++) {
        double s = sin(k * f.p.y[i]), c = cos(k * f.p.y[i]);
        double axe = -amp * s * fabs(c);
        double aye = 4.0 / 3.0 * SPH_SPS_CI * DX * DX * A * A * k * k * k * s * c;
        ex += (f.p.ax[i] - axe) * (f.p.ax[i] - axe);
        ey += (f.p.ay[i] - aye) * (f.p.ay[i] - aye);
    }
    ex = sqrt(ex / (double)f.p.n) / amp;
    ey = sqrt(ey / (double)f.p.n) / amp;
    printf("shear wave: SPS acceleration RMS error a_x %.3e, a_y %.3e of the amplitude %.4e m/s^2 (bound 3e-2)\n",
           ex, ey, amp);
    CHECK(ex < 3e-2 && ey < 3e-2, "shear wave: RMS error a_x %.3e a_y %.3e", ex, ey);
    sph_fluid_free(&f);
}

/* 3. dam break with SPS on */
static void check_dam_break(void)
{
    const double W = 0.2, H = 0.4, TANK = 0.8, g = 9.81;
    sph_params prm;
    sph_params_default(&prm);
    prm.dim = 2;
    prm.dx = DX;
    prm.rho0 = RHO0;
    prm.opt.c0 = 10.0 * sqrt(2.0 * g * H);
    prm.opt.mu = 1e-3;
    prm.opt.alpha = 0.01;
    prm.opt.delta = 0.1;
    prm.body_force[1] = -g;
    prm.opt.sps = 1;
    sph_fluid f;
    char err[256];
    const int64_t n = (int64_t)(W / DX + 0.5) * (int64_t)(H / DX + 0.5);
    if (sph_fluid_init(&f, &prm, n, err, sizeof err) != 0) {
        CHECK(0, "%s", err);
        return;
    }
    double lo[3] = {0, 0, 0}, hi[3] = {W, H, 0}, v0[3] = {0, 0, 0};
    sph_particles_add_box(&f.p, 2, DX, RHO0, lo, hi, v0);
    lahar_body walls[3];
    test_fixed_box2d(&walls[0], TANK / 2, -0.05, TANK / 2 + 0.2, 0.05, 0.005);
    test_fixed_box2d(&walls[1], -0.05, H, 0.05, H + 0.1, 0.005);
    test_fixed_box2d(&walls[2], TANK + 0.05, H, 0.05, H + 0.1, 0.005);
    if (sph_fluid_attach_bodies(&f, 3, walls) != 0) {
        CHECK(0, "attach failed");
        sph_fluid_free(&f);
        return;
    }
    int64_t crossings = 0;
    int steps = 0, finite = 1;
    double rho_dev = 0.0, vmax = 0.0, nut_max = 0.0;
    for (; steps < 400; steps++) {
        double dt = f.primed ? sph_fluid_dt(&f) : 1e-5;
        int64_t c = sph_fluid_step(&f, dt, NULL);
        crossings += c != 0 ? 1 : 0;
        for (int64_t i = 0; i < f.p.n; i++) {
            double v = hypot(f.p.vx[i], f.p.vy[i]);
            if (!isfinite(v) || !isfinite(f.p.rho[i]) || !isfinite(f.p.x[i]) || !isfinite(f.p.y[i]))
                finite = 0;
            vmax = fmax(vmax, v);
            rho_dev = fmax(rho_dev, fabs(f.p.rho[i] / RHO0 - 1.0));
            nut_max = fmax(nut_max, f.sps_nut[i]);
        }
    }
    const double vbound = 1.1 * sqrt(2.0 * g * H);
    printf("dam break with SPS: %d steps to t = %.4f s, crossings %lld, |v|max %.3f m/s (bound %.3f), "
           "|rho/rho0 - 1| max %.3e (bound 5e-2), nu_t max %.3e m^2/s\n",
           steps, f.t, (long long)crossings, vmax, vbound, rho_dev, nut_max);
    CHECK(finite, "dam break: non-finite state");
    CHECK(crossings == 0, "dam break: particles crossed a wall");
    CHECK(vmax < vbound, "dam break: |v|max %.3f above %.3f", vmax, vbound);
    CHECK(rho_dev < 5e-2, "dam break: density deviation %.3e", rho_dev);
    CHECK(nut_max > 0.0, "dam break: SPS never active");
    for (int b = 0; b < 3; b++)
        lahar_shape_free(&walls[b].shape);
    sph_fluid_free(&f);
}

int main(void)
{
    /* the quintic's lattice gradient is within 1e-3 of exact; the cubic's at h = 1.3 dx is 1.05 %
     * off in 2D (a property of the kernel sum, checked against G) */
    check_linear_shear(2, "quintic", 1);
    check_linear_shear(3, "quintic", 1);
    check_linear_shear(2, "cubic", 0);
    check_linear_shear(3, "cubic", 1);
    check_shear_wave();
    check_dam_break();
    if (failures) {
        fprintf(stderr, "%d failure(s)\n", failures);
        return 1;
    }
    printf("all SPS checks passed\n");
    return 0;
}
