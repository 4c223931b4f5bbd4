/* Step cost of the lammps DEM engine against spheropoly on the scene both can hold: n spheres
 * (3D, linear or Hertz) on a jittered lattice dropped into a box of five fixed planes; the pile
 * settles for `warm` seconds in 1 ms coordinator steps, then `meas` seconds are timed. One row per
 * engine and size: bodies, contacts at the end, substeps, microseconds per substep and per
 * body-substep, kinetic energy at the end (the two engines follow different trajectories once
 * tangential contacts slip, so only their order of magnitude is comparable). Single thread
 * (OMP_NUM_THREADS=1): LAMMPS runs serially. Never fails on time.
 *
 * `--dt s`: the coordinator step (default 1 ms); LAMMPS pays a fixed cost per `run` (one per
 * step), so a step of one substep shows that overhead.
 *
 *   bench_dem_lammps [--hertz] [--warm s] [--meas s] [--dt s] [n ...]    (default 100 500 2000) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "dem_engine.h"
#include "dem_test_util.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static void scene(lahar_case *c, int n, int hertz)
{
    const double g[3] = {0, 0, -9.81}, r = 0.01, pitch = 2.2 * r;
    int side = (int)ceil(sqrt(n / 4.0)); /* about 4 layers */
    double L = side * pitch;
    dem_test_case_init(c, 3, g, n + 5);
    int m = hertz ? dem_test_material(c, "rock", LAHAR_CONTACT_HERTZ, 2650.0, 0, 1e8, 0.25, 0.5, 0.5)
                  : dem_test_material(c, "rock", LAHAR_CONTACT_LINEAR, 2650.0, 1e4, 0, 0, 0.5, 0.5);
    const double size[2] = {10 * L, 10 * L};
    const double pf[3] = {0, 0, 0}, nf[3] = {0, 0, 1};
    dem_test_plane(c, "floor", m, pf, nf, size, 0.005);
    for (int a = 0; a < 2; a++)
        for (int s = -1; s <= 1; s += 2) {
            double p[3] = {0, 0, 0}, nn[3] = {0, 0, 0};
            p[a] = -s * (0.5 * L + r);
            nn[a] = s;
            dem_test_plane(c, a ? (s < 0 ? "ymax" : "ymin") : (s < 0 ? "xmax" : "xmin"), m, p, nn, size, 0.005);
        }
    unsigned seed = 12345;
    for (int i = 0; i < n; i++) {
        int ix = i % side, iy = (i / side) % side, iz = i / (side * side);
        seed = seed * 1103515245u + 12345u;
        double jx = ((seed >> 16) % 1000) / 1000.0 - 0.5;
        seed = seed * 1103515245u + 12345u;
        double jy = ((seed >> 16) % 1000) / 1000.0 - 0.5;
        double x[3] = {-0.5 * L + (ix + 0.5) * pitch + 0.1 * r * jx, -0.5 * L + (iy + 0.5) * pitch + 0.1 * r * jy,
                       2 * r + iz * pitch};
        char name[32];
        snprintf(name, sizeof name, "s%d", i);
        dem_test_sphere(c, name, m, r, x, LAHAR_MOTION_FREE);
    }
}

int main(int argc, char **argv)
{
    int hertz = 0, sizes[16], nsize = 0;
    double warm = 0.2, meas = 0.05, dt = 1e-3;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--hertz")) hertz = 1;
        else if (!strcmp(argv[i], "--warm") && i + 1 < argc) warm = atof(argv[++i]);
        else if (!strcmp(argv[i], "--meas") && i + 1 < argc) meas = atof(argv[++i]);
        else if (!strcmp(argv[i], "--dt") && i + 1 < argc) dt = atof(argv[++i]);
        else if (nsize < 16 && atoi(argv[i]) > 0) sizes[nsize++] = atoi(argv[i]);
        else {
            fprintf(stderr, "usage: bench_dem_lammps [--hertz] [--warm s] [--meas s] [--dt s] [n ...]\n");
            return 2;
        }
    }
    if (nsize == 0) sizes[nsize++] = 100, sizes[nsize++] = 500, sizes[nsize++] = 2000;
    static const char *const engines[] = {"spheropoly", "lammps"};
    printf("| engine | law | bodies | contacts | step (s) | substeps | us/substep | us/body-substep | KE end (J) |\n");
    printf("|---|---|---|---|---|---|---|---|---|\n");
    for (int s = 0; s < nsize; s++)
        for (int k = 0; k < 2; k++) {
            const lahar_dem_engine_ops *ops = lahar_dem_engine_find(engines[k]);
            if (!ops) {
                printf("| %s | not built | | | | | | | |\n", engines[k]);
                continue;
            }
            lahar_case c;
            scene(&c, sizes[s], hertz);
            char err[1024];
            lahar_dem_engine *e = ops->create(&c, err, sizeof err);
            if (!e) {
                fprintf(stderr, "%s: %s\n", engines[k], err);
                return 1;
            }
            for (int i = 0; i < (int)lround(warm / dt); i++)
                if (ops->advance(e, dt, NULL, err, sizeof err) < 0) {
                    fprintf(stderr, "%s warm-up: %s\n", engines[k], err);
                    return 1;
                }
            long nsub = 0;
            double t0 = now();
            for (int i = 0; i < (int)lround(meas / dt); i++) {
                int n = ops->advance(e, dt, NULL, err, sizeof err);
                if (n < 0) {
                    fprintf(stderr, "%s: %s\n", engines[k], err);
                    return 1;
                }
                nsub += n;
            }
            double us = (now() - t0) * 1e6 / (double)nsub;
            printf("| %s | %s | %d | %d | %g | %ld | %.1f | %.2f | %.3g |\n", engines[k], hertz ? "hertz" : "linear",
                   sizes[s], ops->ncontacts(e), dt, nsub, us, us / sizes[s], ops->kinetic_energy(e));
            fflush(stdout);
            ops->destroy(e);
            dem_test_case_free(&c);
        }
    return 0;
}
