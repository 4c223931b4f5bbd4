/* The sphere fast path's Verlet list (dem_node/engines/spheropoly/README.md "Sphere fast path"):
 * - a hot gas of 2500 spheres in a walled box (speeds ~1 m/s, the list is rebuilt many times):
 *   after every 100 substeps the engine's contact count equals the brute-force count of
 *   overlapping pairs plus spheres touching a wall (a pair missed by a stale list would show);
 * - a restart written between two list rebuilds continues bit for bit (the list is rebuilt at the
 *   restart positions, the sums do not depend on when it was built);
 * - the same run on 1 and 2 threads, bit for bit. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "dem_test_util.h"

enum { NS = 2500 };
static const double BOX = 0.6;

static double urand(unsigned *s)
{
    *s = *s * 1664525u + 1013904223u;
    return (*s >> 8) / 16777216.0;
}

static void gas_case(lahar_case *c, double *rad)
{
    const double g[3] = {0, 0, 0};
    dem_test_case_init(c, 3, g, NS + 6);
    c->dem_dt_safety = 0.02;
    int m = dem_test_material(c, "rock", LAHAR_CONTACT_HERTZ, 2500.0, 0.0, 1e8, 0.25, 0.9, 0.3);
    unsigned seed = 7u;
    double (*x)[3] = malloc(sizeof(double[3]) * NS);
    int placed = 0;
    while (placed < NS) {
        double r = 0.012 + 0.008 * urand(&seed);
        double p[3] = {r + (BOX - 2 * r) * urand(&seed), r + (BOX - 2 * r) * urand(&seed), r + (BOX - 2 * r) * urand(&seed)};
        int ok = 1;
        for (int j = 0; j < placed && ok; j++) {
            double dx = p[0] - x[j][0], dy = p[1] - x[j][1], dz = p[2] - x[j][2];
            ok = dx * dx + dy * dy + dz * dz >= (r + rad[j]) * (r + rad[j]);
        }
        if (!ok) continue;
        memcpy(x[placed], p, sizeof p);
        rad[placed] = r;
        int b = dem_test_sphere(c, "s", m, r, p, LAHAR_MOTION_FREE);
        for (int d = 0; d < 3; d++) c->bodies[b].v[d] = 2.0 * (urand(&seed) - 0.5);
        placed++;
    }
    free(x);
    /* six walls (planes one core radius outside the box, faces larger than the box) */
    const double wr = 0.002, size[2] = {BOX + 0.2, BOX + 0.2};
    for (int k = 0; k < 6; k++) {
        int ax = k / 2, hi = k % 2;
        double n[3] = {0, 0, 0}, cen[3] = {0.5 * BOX, 0.5 * BOX, 0.5 * BOX};
        n[ax] = hi ? -1.0 : 1.0;
        cen[ax] = hi ? BOX + wr : -wr;
        dem_test_plane(c, "wall", m, cen, n, size, wr);
    }
}

/* Overlapping sphere pairs plus sphere-wall overlaps, brute force. */
static int brute_contacts(const lahar_dem_engine_ops *ops, const lahar_dem_engine *e, const double *rad)
{
    static double x[NS][3];
    for (int i = 0; i < NS; i++) {
        lahar_body_state st;
        ops->get_state(e, i, &st);
        memcpy(x[i], st.x, sizeof x[i]);
    }
    int cnt = 0;
    for (int i = 0; i < NS; i++) {
        for (int j = i + 1; j < NS; j++) {
            double dx = x[i][0] - x[j][0], dy = x[i][1] - x[j][1], dz = x[i][2] - x[j][2];
            cnt += dx * dx + dy * dy + dz * dz < (rad[i] + rad[j]) * (rad[i] + rad[j]);
        }
        for (int d = 0; d < 3; d++) cnt += (x[i][d] < rad[i]) + (x[i][d] > BOX - rad[i]);
    }
    return cnt;
}

static int same_states(const lahar_dem_engine_ops *ops, lahar_dem_engine *a, lahar_dem_engine *b)
{
    for (int i = 0; i < ops->nbody(a); i++) {
        lahar_body_state sa, sb;
        ops->get_state(a, i, &sa);
        ops->get_state(b, i, &sb);
        if (memcmp(&sa, &sb, sizeof sa) != 0) return 0;
    }
    return 1;
}

int main(void)
{
    lahar_case c;
    double rad[NS];
    gas_case(&c, rad);
    const lahar_dem_engine_ops *ops;
    char err[512];
    int maxthr = omp_get_max_threads();
    omp_set_num_threads(1);
    lahar_dem_engine *e = dem_test_engine(&c, &ops);
    double h = ops->stable_dt(e);
    /* 1500 substeps: at ~1 m/s a sphere crosses the skin (0.2 x 1.2 cm) every ~2.4 ms */
    int bad = 0, checks = 0, maxc = 0;
    double travel = 0.0;
    for (int k = 1; k <= 1500; k++) {
        if (ops->advance(e, h, NULL, err, sizeof err) != 1) {
            dem_test_check(0, "advance: %s", err);
            return 1;
        }
        travel += h * 1.0;
        if (k % 150 == 0) {
            int got = ops->ncontacts(e), want = brute_contacts(ops, e, rad);
            checks++;
            maxc = want > maxc ? want : maxc;
            if (got != want) {
                bad++;
                printf("substep %d: engine %d contacts, brute force %d\n", k, got, want);
            }
        }
    }
    dem_test_check(bad == 0 && maxc > 10, "hot gas, 1500 substeps (~%.0f skins of travel): contacts == brute force at all %d checks (up to %d contacts)",
                   travel / 0.0024, checks, maxc);

    /* restart between rebuilds: run 2N == run N + restart + run N, and 1 thread == 2 threads */
    const int N = 150;
    lahar_dem_engine *full = dem_test_engine(&c, &ops), *half = dem_test_engine(&c, &ops);
    omp_set_num_threads(2);
    lahar_dem_engine *two = dem_test_engine(&c, &ops);
    omp_set_num_threads(maxthr);
    for (int k = 0; k < 2 * N; k++) {
        ops->advance(full, h, NULL, err, sizeof err);
        ops->advance(two, h, NULL, err, sizeof err);
    }
    for (int k = 0; k < N; k++) ops->advance(half, h, NULL, err, sizeof err);
    FILE *f = tmpfile();
    dem_test_check(f && ops->write_restart(half, f) == 0, "write_restart");
    lahar_dem_engine *resumed = dem_test_engine(&c, &ops);
    rewind(f);
    dem_test_check(ops->read_restart(resumed, f) == 0, "read_restart");
    fclose(f);
    for (int k = 0; k < N; k++) ops->advance(resumed, h, NULL, err, sizeof err);
    dem_test_check(same_states(ops, full, resumed), "hot gas: %d substeps == %d + restart + %d, bit for bit", 2 * N, N, N);
    dem_test_check(same_states(ops, full, two), "hot gas: 1 thread == 2 threads, bit for bit");
    ops->destroy(e);
    ops->destroy(full);
    ops->destroy(half);
    ops->destroy(two);
    ops->destroy(resumed);
    dem_test_case_free(&c);
    printf("%s\n", dem_test_failures ? "FAILED" : "all passed");
    return dem_test_failures ? 1 : 0;
}
