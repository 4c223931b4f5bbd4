/* The Riemann scheme of the water (sph.scheme: riemann; sph_node/fluid/sph_riemann.h, sph_fluid.h "Riemann
 * scheme"; Zhang, Hu & Adams 2017, J. Comput. Phys. 335:605-620):
 *  1. the interface state of a pair without the limiter is the exact solution of the linear
 *     acoustic Riemann problem: it lies on both characteristics, P* + rho c U* = P_L + rho c U_L
 *     and P* - rho c U* = P_R - rho c U_R (relative 1e-12, 1000 random states), and it is
 *     symmetric (swapping L and R with the velocities' signs gives the same P*, -U*);
 *  2. the limiter: no dissipation for separating pairs (P* = mean), rho eta dU^2/2 for slowly
 *     approaching ones, the acoustic rho c dU/2 once eta dU >= c;
 *  3. water hammer: two water blocks meeting head on at +-U in a box periodic on both axes
 *     (a one-dimensional impact, 2D lattice 100 x 8, dx = 10 mm, c0 = 20 m/s): behind the two
 *     pressure fronts running out at c0 the pressure is the acoustic rho0 c0 U (within 5 %,
 *     the mean over the particles within c0 t / 2 of the plane of impact at t = 0.01 s), with both
 *     scheme: riemann and the delta-SPH scheme, and the total momentum stays 0 (1e-9 of m U). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "sph_fluid.h"
#include "sph_riemann.h"

#include "test_util.h"

static unsigned long long rng_state = 0x9E3779B97F4A7C15ULL;
static double urand(void) /* xorshift64*, deterministic */
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 2685821657736338717ULL) >> 11) * (1.0 / 9007199254740992.0);
}

static void check_acoustic(void)
{
    double worst = 0.0, worst_sym = 0.0;
    for (int k = 0; k < 1000; k++) {
        const double rho = 900 + 200 * urand(), c = 5 + 50 * urand();
        const double pl = 1e5 * (urand() - 0.3), pr = 1e5 * (urand() - 0.3);
        const double ul = 10 * (urand() - 0.5), ur = 10 * (urand() - 0.5);
        const double ps = sph_riemann_pstar(pl, pr, rho, c, ul - ur, 0.0);
        const double us = sph_riemann_ustar(ul, ur, pl, pr, rho, c);
        const double scale = fabs(pl) + fabs(pr) + rho * c * (fabs(ul) + fabs(ur));
        worst = fmax(worst, fabs((ps + rho * c * us) - (pl + rho * c * ul)) / scale);
        worst = fmax(worst, fabs((ps - rho * c * us) - (pr - rho * c * ur)) / scale);
        /* the mirrored problem: R becomes L, the axis reverses */
        const double ps2 = sph_riemann_pstar(pr, pl, rho, c, -ur - (-ul), 0.0);
        const double us2 = sph_riemann_ustar(-ur, -ul, pr, pl, rho, c);
        worst_sym = fmax(worst_sym, (fabs(ps2 - ps) + rho * c * fabs(us2 + us)) / scale);
    }
    printf("acoustic Riemann solver: characteristic relations off by %.2e, mirror symmetry by %.2e (relative)\n",
           worst, worst_sym);
    CHECK(worst < 1e-12, "P*, U* not on the acoustic characteristics (%.3e)", worst);
    CHECK(worst_sym < 1e-12, "P*, U* not symmetric in L and R (%.3e)", worst_sym);
}

static void check_limiter(void)
{
    const double rho = 1000, c = 20, eta = 3, pl = 3000, pr = 1000, pm = 2000;
    const double sep = sph_riemann_pstar(pl, pr, rho, c, -2.0, eta);
    const double slow = sph_riemann_pstar(pl, pr, rho, c, 0.5, eta);
    const double fast = sph_riemann_pstar(pl, pr, rho, c, 10.0, eta);
    printf("limiter: separating %.1f (mean %.1f), dU 0.5: %.1f (expect %.1f), dU 10: %.1f (expect %.1f)\n", sep, pm,
           slow, pm + 0.5 * rho * eta * 0.25, fast, pm + 0.5 * rho * c * 10.0);
    CHECK(fabs(sep - pm) < 1e-12 * pm, "separating pair dissipates");
    CHECK(fabs(slow - (pm + 0.5 * rho * eta * 0.25)) < 1e-12 * pm, "slow approach: not rho eta dU^2 / 2");
    CHECK(fabs(fast - (pm + 0.5 * rho * c * 10.0)) < 1e-12 * pm, "fast approach: not the acoustic rho c dU / 2");
}

/* Two blocks meeting at x = L/2 at +-U; returns the mean pressure within c0 t/2 of the plane and
 * the largest |total momentum| / (M U) over the run. */
static double hammer(int riemann, double *mom)
{
    const int NX = 100, NY = 8;
    const double dx = 0.01, L = NX * dx, rho0 = 1000, c0 = 20, U = 0.5, tend = 0.01;
    sph_params prm;
    sph_params_default(&prm);
    prm.dim = 2;
    prm.dx = dx;
    prm.rho0 = rho0;
    prm.opt.c0 = c0;
    prm.opt.mu = 1e-3;
    if (riemann) {
        prm.opt.scheme = LAHAR_SPH_SCHEME_RIEMANN;
        prm.opt.riemann_limiter = 3.0;
    } else {
        prm.opt.alpha = 0.02;
        prm.opt.delta = 0.1;
    }
    prm.opt.periodic[0] = prm.opt.periodic[1] = 1;
    prm.opt.hi[0] = L;
    prm.opt.hi[1] = NY * dx;
    sph_fluid f;
    char err[256];
    if (sph_fluid_init(&f, &prm, NX * NY, err, sizeof err) != 0) {
        fprintf(stderr, "init: %s\n", err);
        failures++;
        return 0.0;
    }
    double lo[3] = {0, 0, 0}, hi[3] = {L, NY * dx, 0}, v0[3] = {0, 0, 0};
    sph_particles_add_box(&f.p, 2, dx, rho0, lo, hi, v0);
    double mass = 0.0;
    for (int64_t i = 0; i < f.p.n; i++) {
        f.p.vx[i] = f.p.x[i] < 0.5 * L ? U : -U;
        mass += f.p.m[i];
    }
    *mom = 0.0;
    while (f.t < tend - 1e-12) {
        double dt = f.step == 0 ? 0.25 * f.k.h / c0 : sph_fluid_dt(&f);
        if (f.t + dt > tend)
            dt = tend - f.t;
        sph_fluid_step(&f, dt, NULL);
        double px = 0.0;
        for (int64_t i = 0; i < f.p.n; i++)
            px += f.p.m[i] * f.p.vx[i];
        *mom = fmax(*mom, fabs(px) / (mass * U));
    }
    double sum = 0.0;
    int n = 0;
    for (int64_t i = 0; i < f.p.n; i++)
        if (fabs(f.p.x[i] - 0.5 * L) < 0.5 * c0 * f.t) {
            sum += sph_fluid_pressure(&prm, f.p.rho[i]);
            n++;
        }
    sph_fluid_free(&f);
    return n ? sum / n : 0.0;
}

int main(void)
{
    check_acoustic();
    check_limiter();
    const double expect = 1000 * 20 * 0.5;
    for (int riemann = 1; riemann >= 0; riemann--) {
        double mom;
        double p = hammer(riemann, &mom);
        printf("water hammer, %s: mean pressure behind the fronts %.1f Pa, rho0 c0 U = %.1f Pa (%+.2f %%); "
               "momentum drift %.1e m U\n", riemann ? "riemann" : "delta-SPH", p, expect, 100 * (p / expect - 1), mom);
        CHECK(fabs(p / expect - 1) < 0.05, "water hammer pressure %.1f Pa off rho0 c0 U = %.1f Pa by more than 5 %%", p,
              expect);
        CHECK(mom < 1e-9, "total momentum drifts by %.2e M U", mom);
    }
    return failures != 0;
}
