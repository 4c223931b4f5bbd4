/* The SPH node's particles before the WCSPH core drives them: the blocks of a scene fill the
 * analytic count of lattice particles with centres half a spacing inside each block, and free fall
 * under semi-implicit Euler gives the exact velocity v0 + g t and the position error
 * g/2 * sum(dt^2) (analytic for this scheme). */
#include <math.h>
#include <stdio.h>
#include "sph_node.h"

static int failures;
#define CHECK(cond, ...)                                                                           \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__);                                   \
            fprintf(stderr, __VA_ARGS__);                                                          \
            fputc('\n', stderr);                                                                   \
            failures++;                                                                            \
        }                                                                                          \
    } while (0)

int main(void)
{
    const double dx = 0.01;
    const lahar_particle_block blocks[2] = {
        {.name = "a", .lo = {0, 0, 0}, .hi = {0.1, 0.05, 0.2}, .v = {0, 0, 0}},
        {.name = "b", .lo = {1, 0, 0}, .hi = {1.03, 0.02, 0.01}, .v = {1, 0, 2}},
    };
    sph_particles p;
    int64_t n = lahar_sph_node_fill(&p, 3, dx, 1000.0, 2, blocks);
    CHECK(n == 10 * 5 * 20 + 3 * 2 * 1, "3D lattice: %lld particles, expected %d", (long long)n, 10 * 5 * 20 + 6);
    CHECK(fabs(p.x[0] - 0.005) < 1e-15 && fabs(p.z[0] - 0.005) < 1e-15, "first centre (%g, %g, %g)", p.x[0], p.y[0],
          p.z[0]);
    CHECK(p.n == p.cap, "arrays sized %lld for %lld particles", (long long)p.cap, (long long)p.n);
    sph_particles_free(&p);
    n = lahar_sph_node_fill(&p, 2, dx, 1000.0, 1, blocks);
    CHECK(n == 10 * 5, "2D lattice: %lld particles, expected 50", (long long)n);
    sph_particles_free(&p);

    /* free fall with the CFL step the node proposes */
    n = lahar_sph_node_fill(&p, 3, dx, 1000.0, 2, blocks);
    const double g[3] = {0, 0, -9.81};
    double t = 0.0, sum_dt2 = 0.0;
    int steps = 0;
    while (t < 0.5) {
        double dt = lahar_sph_node_fall_dt(&p, g, dx);
        double vmax = 0.0;
        for (int64_t i = 0; i < p.n; i++)
            vmax = fmax(vmax, sqrt(p.vx[i] * p.vx[i] + p.vy[i] * p.vy[i] + p.vz[i] * p.vz[i]));
        CHECK(fabs(dt - 0.25 * dx / (vmax + sqrt(9.81 * dx))) < 1e-15, "CFL step %g", dt);
        lahar_sph_node_fall(&p, g, dt);
        t += dt;
        sum_dt2 += dt * dt;
        steps++;
    }
    int64_t last = p.n - 1; /* a particle of the second block: v0 = (1, 0, 2) */
    double z0 = 0.005, x0 = 1.025;
    double vz_exact = 2.0 - 9.81 * t, z_exact = z0 + 2.0 * t - 0.5 * 9.81 * t * t;
    CHECK(fabs(p.vz[last] - vz_exact) < 1e-12, "vz %.17g, exact %.17g", p.vz[last], vz_exact);
    CHECK(fabs(p.x[last] - (x0 + t)) < 1e-12, "x %.17g, exact %.17g", p.x[last], x0 + t);
    /* semi-implicit Euler: z_n = z(t_n) - g/2 sum dt^2, i.e. 0.5 * 9.81 * sum_dt2 below the parabola */
    double err = p.z[last] - z_exact;
    CHECK(fabs(err + 0.5 * 9.81 * sum_dt2) < 1e-12, "z error %.3e, analytic %.3e", err, -0.5 * 9.81 * sum_dt2);
    printf("sph: %d steps to t = %.4f s, z error %.3e m (analytic %.3e)\n", steps, t, err, -0.5 * 9.81 * sum_dt2);
    sph_particles_free(&p);
    if (failures)
        return 1;
    printf("PASS test_sph_particles\n");
    return 0;
}
