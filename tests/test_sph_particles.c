/* The SPH node's initial particles: the blocks of a scene give the analytic count of lattice
 * particles with centres half a spacing inside each block, and lattice points inside a body are
 * left out (counted independently here) and those within its coupling halo dx/2 moved out to it,
 * so no particle starts inside a DEM body or overlapping it. And the particle arrays start on
 * different cache-line offsets within their pages (common/memory/soa_alloc.h): with glibc's calloc
 * every large array starts at offset 16 and the hot loops evict their own lines. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include "shape_build.h"
#include "soa_alloc.h"
#include "sph_node.h"

#include "test_util.h"

/* The particle arrays a pass streams at one index: distinct cache lines modulo the page, and zeroed. */
static void check_staggered(void)
{
    sph_particles p;
    CHECK(sph_particles_init(&p, 100000) == 0, "100,000 particles");
    const double *a[] = {p.x, p.y, p.z, p.vx, p.vy, p.vz, p.rho, p.p, p.m, p.ax, p.ay, p.az, p.drho, p.vhx, p.vhy, p.vhz, p.rhoh, p.scratch_d};
    const int na = (int)(sizeof a / sizeof a[0]);
    unsigned line[sizeof a / sizeof a[0]];
    for (int k = 0; k < na; k++) {
        uintptr_t off = (uintptr_t)a[k] % 4096u;
        CHECK(off % 64u == 0, "array %d at page offset %u: not on a cache line", k, (unsigned)off);
        line[k] = (unsigned)(off / 64u);
        for (int j = 0; j < k; j++)
            CHECK(line[j] != line[k], "arrays %d and %d both start at page offset %u", j, k, line[k] * 64u);
        CHECK(a[k][0] == 0.0 && a[k][99999] == 0.0, "array %d not zeroed", k);
    }
    sph_particles_free(&p);
    /* the allocator itself: LAHAR_SOA_COLOURS consecutive arrays, all offsets distinct; an
     * impossible size refused */
    void *b[LAHAR_SOA_COLOURS];
    unsigned seen[64] = {0};
    for (int k = 0; k < LAHAR_SOA_COLOURS; k++) {
        b[k] = lahar_soa_calloc(1000, 8);
        CHECK(b[k] != NULL, "allocation %d", k);
        unsigned l = (unsigned)((uintptr_t)b[k] % 4096u / 64u);
        CHECK(l > 0 && !seen[l], "allocation %d at line %u of its page (0 or taken)", k, l);
        seen[l] = 1;
    }
    for (int k = 0; k < LAHAR_SOA_COLOURS; k++)
        lahar_soa_free(b[k]);
    CHECK(lahar_soa_calloc(SIZE_MAX / 4, 8) == NULL, "an overflowing size must give NULL");
}

int main(void)
{
    check_staggered();
    const double dx = 0.01;
    lahar_particle_block blocks[2] = {
        {.name = "a", .lo = {0, 0, 0}, .hi = {0.1, 0.05, 0.2}, .v = {0, 0, 0}},
        {.name = "b", .lo = {1, 0, 0}, .hi = {1.03, 0.02, 0.01}, .v = {1, 0, 2}},
    };
    lahar_case c;
    memset(&c, 0, sizeof c);
    c.dim = 3;
    c.sph_dx = dx;
    c.sph_density = 1000.0;
    c.nblock = 2;
    c.blocks = blocks;

    sph_particles p;
    int64_t n = lahar_sph_node_fill(&p, &c);
    CHECK(n == 10 * 5 * 20 + 3 * 2 * 1, "3D lattice: %lld particles, expected %d", (long long)n, 10 * 5 * 20 + 6);
    CHECK(fabs(p.x[0] - 0.005) < 1e-15 && fabs(p.z[0] - 0.005) < 1e-15, "first centre (%g, %g, %g)", p.x[0], p.y[0],
          p.z[0]);
    CHECK(fabs(p.m[0] - 1000.0 * dx * dx * dx) < 1e-15, "mass %g, expected rho0 dx^3", p.m[0]);
    CHECK(p.vz[n - 1] == 2.0 && p.vx[n - 1] == 1.0, "block b keeps its velocity");
    CHECK(p.n == p.cap, "arrays sized %lld for %lld particles", (long long)p.cap, (long long)p.n);
    sph_particles_free(&p);

    c.dim = 2;
    c.nblock = 1;
    n = lahar_sph_node_fill(&p, &c);
    CHECK(n == 10 * 5, "2D lattice: %lld particles, expected 50", (long long)n);
    sph_particles_free(&p);

    /* A disc of radius R (not a lattice distance) in block a: the points with |x - centre| < R
     * are left out, and those within the coupling's halo dx/2 of its surface (sph_coupling.h)
     * are moved out to it along the radius. */
    lahar_body disc;
    memset(&disc, 0, sizeof disc);
    snprintf(disc.name, sizeof disc.name, "disc");
    const double R = 0.0173, centre[3] = {0.05, 0.025, 0.0};
    CHECK(lahar_shape_make_sphere(&disc.shape, R) == 0, "disc shape");
    memcpy(disc.x, centre, sizeof centre);
    disc.q[0] = 1.0;
    disc.mass = 1.0;
    disc.convex = 1;
    c.nbody = 1;
    c.bodies = &disc;
    int64_t expected = 0;
    for (int i = 0; i < 10; i++)
        for (int j = 0; j < 5; j++) {
            double x = (i + 0.5) * dx - centre[0], y = (j + 0.5) * dx - centre[1];
            expected += sqrt(x * x + y * y) >= R;
        }
    n = lahar_sph_node_fill(&p, &c);
    CHECK(n == expected && expected < 50, "2D lattice around a disc: %lld particles, expected %lld", (long long)n,
          (long long)expected);
    for (int64_t i = 0; i < p.n; i++) {
        double d = hypot(p.x[i] - centre[0], p.y[i] - centre[1]);
        CHECK(d >= R + 0.5 * dx * (1.0 - 1e-6), "particle %lld at distance %g inside the disc of radius %g or its halo dx/2",
              (long long)i, d, R);
    }
    sph_particles_free(&p);
    lahar_shape_free(&disc.shape);
    if (failures)
        return 1;
    printf("PASS test_sph_particles (%lld of 50 lattice points outside the disc, none in its halo)\n", (long long)expected);
    return 0;
}
