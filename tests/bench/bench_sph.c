/* SPH step cost : dam breaks built through the solver core (sph_fluid
 * API; the tank walls are fixed DEM bodies seen through the coupling of sph_coupling.h), stepped
 * N times on 1 and 2 threads from the same initial state. Prints one table row per case and
 * thread count: particles, steps, wall time, CPU time (all threads), particle-steps per second, speed-up over 1 thread,
 * bytes per particle (heap held by the solver after the steps, measured with mallinfo2), and a digest of the final
 * state (equal digest = bitwise equal result). Never fails on time.
 *
 *   2d  80,000 water particles: a 0.4 x 0.8 m column at dx = 2 mm in a 1.6 m tank (the set-up of
 *       the issue: Wendland C2, h = 1.41 dx, one force pass per step, c0 = 40 m/s, alpha 0.02,
 *       delta 0.1, mu 1e-3, CFL 0.25);
 *   3d  100,000 water particles: a 0.5 x 0.4 x 0.5 m column at dx = 10 mm in a 1.6 x 0.4 m
 *       tank, same settings with c0 = 30 m/s.
 * The time step is the solver's own proposal (sph_fluid_dt), so a row runs at the accuracy the
 * settings give; --ref FILE compares the final state with the one saved by --save-ref FILE (by
 * particle id: largest position difference in dx, relative L2 difference of the velocities), which
 * is how an optimisation of the solver shows it changed nothing but round-off.
 *
 *   bench_sph [--steps2d n] [--steps3d n] [--threads 1,2] [--repeat n] [--save-ref FILE] [--ref FILE] [2d] [3d]
 *
 * --repeat n runs n rounds of the thread counts, alternating, and ends each case with the median
 * particle-steps per second per thread count and the median of the rounds' speed-ups.
 *
 * Profiling only the timed part:
 *   valgrind --tool=callgrind --collect-atstart=no --toggle-collect='bench_measure*' bench_sph ...
 * Wall times on a shared machine vary: run it more than once. */
#include <malloc.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "shape_build.h"
#include "sph_fluid.h"

typedef struct {
    const char *name;
    int dim;
    double dx, c0;
    double col[3];  /* water column [0, col) */
    double tank[3]; /* inner tank [0, tank) (2D: x, y) */
    int nbody;
    lahar_body walls[6];
} bench_case;

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* CPU time of the process (all threads): on a loaded machine the 1-thread figure is the steadier
 * measure of the work done. */
static double cpu_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* A fixed wall: box [lo, hi) (world frame), swept radius R, vertices in world coordinates. */
static void wall(lahar_body *b, int dim, const double lo[3], const double hi[3])
{
    memset(b, 0, sizeof *b);
    const double R = 0.002;
    double half[3], t[3];
    for (int a = 0; a < 3; a++) {
        half[a] = 0.5 * (hi[a] - lo[a]) - R;
        t[a] = 0.5 * (hi[a] + lo[a]);
    }
    int rc = dim == 2 ? lahar_shape_make_box2d(&b->shape, half, R) : lahar_shape_make_box(&b->shape, half, R);
    if (rc != 0) {
        fprintf(stderr, "bench_sph: cannot build a wall\n");
        exit(1);
    }
    if (dim == 2)
        t[2] = 0.0;
    lahar_shape_transform(&b->shape, NULL, t, 1.0);
    b->motion = LAHAR_MOTION_FIXED;
    b->convex = 1;
    b->q[0] = 1.0;
}

static void case_walls(bench_case *c)
{
    const double T = 0.02; /* wall thickness */
    const double L = c->tank[0], H = c->tank[1] + 0.2, W = c->tank[2];
    if (c->dim == 2) {
        double f0[3] = {-T, -T, 0}, f1[3] = {L + T, 0, 0};
        double l0[3] = {-T, 0, 0}, l1[3] = {0, H, 0};
        double r0[3] = {L, 0, 0}, r1[3] = {L + T, H, 0};
        wall(&c->walls[0], 2, f0, f1);
        wall(&c->walls[1], 2, l0, l1);
        wall(&c->walls[2], 2, r0, r1);
        c->nbody = 3;
        return;
    }
    /* 3D: z is up */
    const double Hz = c->tank[2] + 0.2, Wy = c->tank[1];
    (void)H, (void)W;
    double lo[5][3] = {{-T, -T, -T}, {-T, -T, 0}, {L, -T, 0}, {-T, -T, 0}, {-T, Wy, 0}};
    double hi[5][3] = {{L + T, Wy + T, 0}, {0, Wy + T, Hz}, {L + T, Wy + T, Hz}, {L + T, 0, Hz}, {L + T, Wy + T, Hz}};
    for (int b = 0; b < 5; b++)
        wall(&c->walls[b], 3, lo[b], hi[b]);
    c->nbody = 5;
}

static void params(const bench_case *c, sph_params *prm)
{
    sph_params_default(prm);
    prm->dim = c->dim;
    snprintf(prm->opt.kernel, sizeof prm->opt.kernel, "%s", "wendland2");
    prm->dx = c->dx;
    prm->opt.h_over_dx = 1.41;
    prm->rho0 = 1000.0;
    prm->opt.c0 = c->c0;
    prm->opt.mu = 1e-3;
    prm->opt.alpha = 0.02;
    prm->opt.delta = 0.1;
    prm->body_force[c->dim == 2 ? 1 : 2] = -9.81;
}

/* The fluid of case c with its particles and walls; exits on failure. */
static void setup(bench_case *c, sph_fluid *f)
{
    sph_params prm;
    params(c, &prm);
    char err[256];
    int64_t cap = 1;
    for (int a = 0; a < c->dim; a++)
        cap *= (int64_t)floor(c->col[a] / c->dx + 1e-9);
    if (sph_fluid_init(f, &prm, cap, err, sizeof err) != 0) {
        fprintf(stderr, "bench_sph: %s\n", err);
        exit(1);
    }
    double lo[3] = {0, 0, 0}, hi[3] = {c->col[0], c->col[1], c->dim == 3 ? c->col[2] : 0}, v0[3] = {0, 0, 0};
    if (sph_particles_add_box(&f->p, c->dim, c->dx, prm.rho0, lo, hi, v0) != cap ||
        sph_fluid_attach_bodies(f, c->nbody, c->walls) != 0) {
        fprintf(stderr, "bench_sph: cannot set up %s\n", c->name);
        exit(1);
    }
}

/* The timed part, a function of its own so that a profiler can collect only it. */
static __attribute__((noinline)) int bench_measure(sph_fluid *f, int nsteps)
{
    for (int k = 0; k < nsteps; k++) {
        double dt = f->primed ? sph_fluid_dt(f) : 0.25 * f->k.h / f->prm.opt.c0;
        if (sph_fluid_step(f, dt, NULL) != 0)
            return -1;
    }
    return 0;
}

/* FNV-1a over positions, velocities and densities in id order. */
static unsigned long long digest(const sph_fluid *f, const int64_t *order)
{
    const sph_particles *p = &f->p;
    unsigned long long h = 1469598103934665603ull;
    for (int64_t k = 0; k < p->n; k++) {
        int64_t i = order[k];
        double v[7] = {p->x[i], p->y[i], p->z[i], p->vx[i], p->vy[i], p->vz[i], p->rho[i]};
        const unsigned char *b = (const unsigned char *)v;
        for (size_t m = 0; m < sizeof v; m++)
            h = (h ^ b[m]) * 1099511628211ull;
    }
    return h;
}

/* order[id] = index of the particle with that id (ids are 0 .. n-1 here). */
static void id_order(const sph_fluid *f, int64_t *order)
{
    for (int64_t i = 0; i < f->p.n; i++)
        order[f->p.id[i]] = i;
}

static size_t heap_bytes(void)
{
    struct mallinfo2 mi = mallinfo2();
    return mi.uordblks + mi.hblkhd;
}

/* Save (x, y, z, vx, vy, vz) in id order, or compare with a saved file. */
static void reference(const bench_case *c, const sph_fluid *f, const int64_t *order, const char *save, const char *cmp,
                      int steps)
{
    const sph_particles *p = &f->p;
    char path[1024];
    if (save) {
        snprintf(path, sizeof path, "%s.%s", save, c->name);
        FILE *o = fopen(path, "wb");
        if (!o) {
            fprintf(stderr, "bench_sph: cannot write %s\n", path);
            return;
        }
        int64_t hdr[2] = {p->n, steps};
        fwrite(hdr, sizeof hdr, 1, o);
        for (int64_t k = 0; k < p->n; k++) {
            int64_t i = order[k];
            double v[6] = {p->x[i], p->y[i], p->z[i], p->vx[i], p->vy[i], p->vz[i]};
            fwrite(v, sizeof v, 1, o);
        }
        fclose(o);
        printf("# %s: final state saved to %s\n", c->name, path);
    }
    if (cmp) {
        snprintf(path, sizeof path, "%s.%s", cmp, c->name);
        FILE *in = fopen(path, "rb");
        int64_t hdr[2];
        if (!in || fread(hdr, sizeof hdr, 1, in) != 1 || hdr[0] != p->n || hdr[1] != steps) {
            fprintf(stderr, "bench_sph: %s is not a reference of %s with %d steps\n", path, c->name, steps);
            if (in)
                fclose(in);
            return;
        }
        double dxmax = 0.0, dv2 = 0.0, v2 = 0.0;
        for (int64_t k = 0; k < p->n; k++) {
            int64_t i = order[k];
            double v[6];
            if (fread(v, sizeof v, 1, in) != 1)
                break;
            double d[3] = {p->x[i] - v[0], p->y[i] - v[1], p->z[i] - v[2]};
            dxmax = fmax(dxmax, sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
            double e[3] = {p->vx[i] - v[3], p->vy[i] - v[4], p->vz[i] - v[5]};
            dv2 += e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
            v2 += v[3] * v[3] + v[4] * v[4] + v[5] * v[5];
        }
        fclose(in);
        printf("# %s against %s: largest position difference %.3g dx, velocity L2 difference %.3g (relative)\n",
               c->name, path, dxmax / c->dx, v2 > 0.0 ? sqrt(dv2 / v2) : sqrt(dv2));
    }
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

#define BENCH_MAX_REPEAT 32

static void run_round(bench_case *c, int steps, const int *thr, int nthr, const char *save, const char *cmp, int last,
                      double rate[][BENCH_MAX_REPEAT], double ratio[][BENCH_MAX_REPEAT], int round);

/* One row per round and thread count; with repeat > 1 the thread counts alternate round by round
 * (1, 2, 1, 2, ...: on a VM whose speed drifts, each speed-up compares runs a few seconds apart)
 * and a last line gives the medians. */
static void run_case(bench_case *c, int steps, const int *thr, int nthr, int repeat, const char *save,
                     const char *cmp)
{
    double rate[8][BENCH_MAX_REPEAT], ratio[8][BENCH_MAX_REPEAT];
    for (int r = 0; r < repeat; r++)
        run_round(c, steps, thr, nthr, save, cmp, r == repeat - 1, rate, ratio, r);
    if (repeat < 2)
        return;
    printf("# %s, median of %d rounds:", c->name, repeat);
    for (int t = 0; t < nthr; t++) {
        printf(" %d thread%s %.3g particle-steps/s", thr[t], thr[t] == 1 ? "" : "s", median(rate[t], repeat));
        if (thr[t] != 1 && ratio[t][0] > 0.0)
            printf(" (speed-up %.2f)", median(ratio[t], repeat));
        printf(t == nthr - 1 ? "\n" : ";");
    }
}

static void run_round(bench_case *c, int steps, const int *thr, int nthr, const char *save, const char *cmp, int last,
                      double rate[][BENCH_MAX_REPEAT], double ratio[][BENCH_MAX_REPEAT], int round)
{
    double t1 = 0.0;
    for (int t = 0; t < nthr; t++) {
        omp_set_num_threads(thr[t]);
        size_t h0 = heap_bytes();
        sph_fluid f;
        setup(c, &f);
        double t0 = now(), c0 = cpu_now();
        int rc = bench_measure(&f, steps);
        double wall_s = now() - t0, cpu_s = cpu_now() - c0;
        size_t bytes = heap_bytes() - h0; /* after the steps: with the grown cell table and contact list */
        if (rc != 0) {
            fprintf(stderr, "bench_sph: %s: a step failed (%lld crossings)\n", c->name, (long long)f.crossings);
            sph_fluid_free(&f);
            exit(1);
        }
        if (thr[t] == 1)
            t1 = wall_s;
        double rhomax = 0.0;
        for (int64_t i = 0; i < f.p.n; i++)
            rhomax = fmax(rhomax, fabs(f.p.rho[i] / f.prm.rho0 - 1.0));
        int64_t *order = malloc((size_t)f.p.n * sizeof *order);
        if (!order)
            exit(1);
        id_order(&f, order);
        char speedup[32] = "-";
        if (t1 > 0.0)
            snprintf(speedup, sizeof speedup, "%.2f", t1 / wall_s);
        rate[t][round] = (double)f.p.n * steps / wall_s;
        ratio[t][round] = t1 > 0.0 ? t1 / wall_s : 0.0;
        printf("| %s | %lld | %d | %.3f | %.3f | %.3g | %d | %s | %.0f | %.4g | %.3g | %016llx |\n", c->name,
               (long long)f.p.n, steps, wall_s, cpu_s, (double)f.p.n * steps / wall_s, thr[t], speedup,
               (double)bytes / (double)f.p.n, f.t, rhomax, digest(&f, order));
        fflush(stdout);
        if (t == nthr - 1 && last)
            reference(c, &f, order, save, cmp, steps);
        free(order);
        sph_fluid_free(&f);
    }
}

int main(int argc, char **argv)
{
    int steps2 = 100, steps3 = 40, thr[8] = {1, 2}, nthr = 2, want2 = 0, want3 = 0, repeat = 1;
    const char *save = NULL, *cmp = NULL;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--steps2d") && i + 1 < argc)
            steps2 = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--steps3d") && i + 1 < argc)
            steps3 = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--save-ref") && i + 1 < argc)
            save = argv[++i];
        else if (!strcmp(argv[i], "--ref") && i + 1 < argc)
            cmp = argv[++i];
        else if (!strcmp(argv[i], "--repeat") && i + 1 < argc) {
            repeat = atoi(argv[++i]);
            if (repeat < 1 || repeat > BENCH_MAX_REPEAT) {
                fprintf(stderr, "bench_sph: --repeat takes 1 .. %d rounds (got %s)\n", BENCH_MAX_REPEAT, argv[i]);
                return 2;
            }
        }
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc) {
            nthr = 0;
            for (char *s = strtok(argv[++i], ","); s && nthr < 8; s = strtok(NULL, ","))
                thr[nthr++] = atoi(s);
        } else if (!strcmp(argv[i], "2d"))
            want2 = 1;
        else if (!strcmp(argv[i], "3d"))
            want3 = 1;
        else {
            fprintf(stderr, "usage: bench_sph [--steps2d n] [--steps3d n] [--threads 1,2] [--repeat n] "
                            "[--save-ref FILE] [--ref FILE] [2d] [3d]\n");
            return 2;
        }
    }
    if (!want2 && !want3)
        want2 = want3 = 1;
    printf("| case | particles | steps | wall s | CPU s | particle-steps/s | threads | speed-up | bytes/particle | t end s | "
           "max abs(rho/rho0-1) | digest |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    if (want2) {
        bench_case c = {.name = "dam_break_2d_80k", .dim = 2, .dx = 0.002, .c0 = 40.0, .col = {0.4, 0.8, 0.0},
                        .tank = {1.6, 1.0, 0.0}};
        case_walls(&c);
        run_case(&c, steps2, thr, nthr, repeat, save, cmp);
        for (int b = 0; b < c.nbody; b++)
            lahar_shape_free(&c.walls[b].shape);
    }
    if (want3) {
        bench_case c = {.name = "dam_break_3d_100k", .dim = 3, .dx = 0.01, .c0 = 30.0, .col = {0.5, 0.4, 0.5},
                        .tank = {1.6, 0.4, 0.8}};
        case_walls(&c);
        run_case(&c, steps3, thr, nthr, repeat, save, cmp);
        for (int b = 0; b < c.nbody; b++)
            lahar_shape_free(&c.walls[b].shape);
    }
    return 0;
}
