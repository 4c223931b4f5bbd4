/* Reproducibility and scale of the spheropoly engine:
 * - a pile of spheres and boxes: N steps == N/2 steps, restart, N/2 steps, bit for bit;
 * - the same run with 1 and 2 OpenMP threads is bitwise identical;
 * - 3000 spheres: the grid broad phase finds exactly the overlapping pairs that a brute-force
 *   O(N^2) check finds, before and after moving;
 * - a sphere shot into the floor far too fast is reported as an instability naming the body. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "dem_test_util.h"
#include "vec.h"

static double urand(unsigned *s)
{
    *s = *s * 1664525u + 1013904223u;
    return (*s >> 8) / 16777216.0;
}

static void pile_case(lahar_case *c)
{
    const double gv[3] = {0, 0, -9.81};
    dem_test_case_init(c, 3, gv, 64);
    int m = dem_test_material(c, "rock", LAHAR_CONTACT_LINEAR, 2500.0, 1e6, 0, 0, 0.4, 0.5);
    int h = dem_test_material(c, "granite", LAHAR_CONTACT_HERTZ, 2700.0, 1e6, 5e8, 0.25, 0.6, 0.4);
    const double centre[3] = {0, 0, 0}, n[3] = {0, 0, 1}, size[2] = {3, 3};
    dem_test_plane(c, "floor", m, centre, n, size, 0.02);
    unsigned seed = 7u;
    for (int k = 0; k < 40; k++) {
        double x[3] = {0.3 * (k % 4) - 0.45, 0.3 * ((k / 4) % 4) - 0.45, 0.2 + 0.3 * (k / 16)};
        char name[16];
        snprintf(name, sizeof name, "rock%d", k);
        if (k % 2 == 0) {
            dem_test_sphere(c, name, k % 4 == 0 ? m : h, 0.06 + 0.04 * urand(&seed), x, LAHAR_MOTION_FREE);
        } else {
            quat q = q_normalize((quat){urand(&seed) - 0.5, urand(&seed) - 0.5, urand(&seed) - 0.5, urand(&seed) - 0.5});
            double q4[4], half[3] = {0.05 + 0.05 * urand(&seed), 0.05 + 0.03 * urand(&seed), 0.04};
            q_store(q, q4);
            dem_test_box(c, name, k % 3 == 0 ? h : m, half, 0.02, x, q4, LAHAR_MOTION_FREE);
        }
        lahar_body *b = &c->bodies[c->nbody - 1];
        b->v[0] = urand(&seed) - 0.5;
        b->v[1] = urand(&seed) - 0.5;
        b->w[2] = 4.0 * (urand(&seed) - 0.5);
    }
}

static void run(const lahar_dem_engine_ops *ops, lahar_dem_engine *e, int n)
{
    char err[512];
    for (int k = 0; k < n; k++)
        if (ops->advance(e, 2e-3, NULL, err, sizeof err) < 0) {
            dem_test_check(0, "advance: %s", err);
            return;
        }
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

static int count_overlaps(int n, const double (*x)[3], const double *r)
{
    int cnt = 0;
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++) {
            double dx = x[i][0] - x[j][0], dy = x[i][1] - x[j][1], dz = x[i][2] - x[j][2];
            if (dx * dx + dy * dy + dz * dz < (r[i] + r[j]) * (r[i] + r[j])) cnt++;
        }
    return cnt;
}

int main(void)
{
    const int N = 200;
    lahar_case c;
    pile_case(&c);
    const lahar_dem_engine_ops *ops;
    /* restart */
    lahar_dem_engine *full = dem_test_engine(&c, &ops);
    run(ops, full, N);
    lahar_dem_engine *half = dem_test_engine(&c, &ops);
    run(ops, half, N / 2);
    FILE *f = tmpfile();
    dem_test_check(f && ops->write_restart(half, f) == 0, "write_restart");
    ops->destroy(half);
    rewind(f);
    lahar_dem_engine *resumed = dem_test_engine(&c, &ops);
    dem_test_check(ops->read_restart(resumed, f) == 0, "read_restart");
    fclose(f);
    run(ops, resumed, N / 2);
    dem_test_check(ops->ncontacts(full) > 20, "pile has %d contacts after 0.4 s (a real test of the history)",
                   ops->ncontacts(full));
    dem_test_check(same_states(ops, full, resumed), "run %d == run %d + restart + run %d, bit for bit", N, N / 2, N / 2);
    ops->destroy(resumed);
    /* thread count */
    int maxthr = omp_get_max_threads();
    omp_set_num_threads(1);
    lahar_dem_engine *one = dem_test_engine(&c, &ops);
    omp_set_num_threads(2);
    lahar_dem_engine *two = dem_test_engine(&c, &ops);
    omp_set_num_threads(maxthr);
    run(ops, one, N);
    run(ops, two, N);
    dem_test_check(same_states(ops, one, two) && same_states(ops, one, full), "1 thread == 2 threads, bit for bit");
    ops->destroy(one);
    ops->destroy(two);
    ops->destroy(full);
    dem_test_case_free(&c);

    /* broad phase against brute force */
    const int nsph = 3000;
    const double g0[3] = {0, 0, 0};
    dem_test_case_init(&c, 3, g0, nsph);
    c.dem_dt_safety = 0.02;
    int m = dem_test_material(&c, "rock", LAHAR_CONTACT_LINEAR, 2500.0, 1e6, 0, 0, 0.5, 0.3);
    double (*x)[3] = malloc(sizeof(double[3]) * nsph), *r = malloc(sizeof(double) * nsph);
    unsigned seed = 99u;
    int placed = 0;
    while (placed < nsph) {
        double p[3] = {3.0 * urand(&seed), 3.0 * urand(&seed), 3.0 * urand(&seed)}, rad = 0.05 + 0.05 * urand(&seed);
        int ok = 1;
        for (int j = 0; j < placed && ok; j++) { /* overlaps at most 0.2 of the smaller radius */
            double dx = p[0] - x[j][0], dy = p[1] - x[j][1], dz = p[2] - x[j][2];
            double lim = rad + r[j] - 0.2 * fmin(rad, r[j]);
            if (dx * dx + dy * dy + dz * dz < lim * lim) ok = 0;
        }
        if (!ok) continue;
        memcpy(x[placed], p, sizeof p);
        r[placed] = rad;
        dem_test_sphere(&c, "s", m, rad, p, LAHAR_MOTION_FREE);
        c.bodies[placed].v[0] = urand(&seed) - 0.5;
        c.bodies[placed].v[1] = urand(&seed) - 0.5;
        c.bodies[placed].v[2] = urand(&seed) - 0.5;
        placed++;
    }
    omp_set_num_threads(1);
    lahar_dem_engine *e1 = dem_test_engine(&c, &ops);
    omp_set_num_threads(2);
    lahar_dem_engine *e = dem_test_engine(&c, &ops);
    omp_set_num_threads(maxthr);
    int brute = count_overlaps(nsph, (const double(*)[3])x, r);
    dem_test_check(ops->ncontacts(e) == brute && brute > 100, "3000 spheres at start: grid finds %d contacts, brute force %d",
                   ops->ncontacts(e), brute);
    double t0 = omp_get_wtime();
    char err[512];
    int nsub = 0;
    for (int k = 0; k < 20; k++) {
        int n = ops->advance(e, ops->stable_dt(e), NULL, err, sizeof err);
        if (n < 0) {
            dem_test_check(0, "advance: %s", err);
            break;
        }
        nsub += n;
    }
    double t1 = omp_get_wtime();
    /* >= 512 pairs: the narrow phase really ran on a thread team here */
    for (int k = 0; k < 20; k++)
        if (ops->advance(e1, ops->stable_dt(e1), NULL, err, sizeof err) < 0) break;
    dem_test_check(same_states(ops, e, e1), "3000 spheres, 20 substeps: 1 thread == 2 threads, bit for bit");
    ops->destroy(e1);
    for (int i = 0; i < nsph; i++) {
        lahar_body_state st;
        ops->get_state(e, i, &st);
        memcpy(x[i], st.x, sizeof st.x);
    }
    brute = count_overlaps(nsph, (const double(*)[3])x, r);
    dem_test_check(ops->ncontacts(e) == brute, "3000 spheres after %d substeps (%.2f ms each): grid %d, brute force %d", nsub,
                   1e3 * (t1 - t0) / nsub, ops->ncontacts(e), brute);
    ops->destroy(e);
    dem_test_case_free(&c);
    free(x);
    free(r);

    /* the same in 2D (9-cell neighbourhood): 2000 discs */
    const int ndisc = 2000;
    dem_test_case_init(&c, 2, g0, ndisc);
    m = dem_test_material(&c, "rock", LAHAR_CONTACT_LINEAR, 2500.0, 1e6, 0, 0, 0.5, 0.3);
    x = malloc(sizeof(double[3]) * ndisc);
    r = malloc(sizeof(double) * ndisc);
    placed = 0;
    while (placed < ndisc) {
        double p[3] = {4.0 * urand(&seed), 4.0 * urand(&seed), 0.0}, rad = 0.03 + 0.03 * urand(&seed);
        int ok = 1;
        for (int j = 0; j < placed && ok; j++) {
            double dx = p[0] - x[j][0], dy = p[1] - x[j][1];
            double lim = rad + r[j] - 0.2 * fmin(rad, r[j]);
            if (dx * dx + dy * dy < lim * lim) ok = 0;
        }
        if (!ok) continue;
        memcpy(x[placed], p, sizeof p);
        r[placed] = rad;
        dem_test_sphere(&c, "d", m, rad, p, LAHAR_MOTION_FREE);
        placed++;
    }
    e = dem_test_engine(&c, &ops);
    brute = count_overlaps(ndisc, (const double(*)[3])x, r);
    dem_test_check(ops->ncontacts(e) == brute && brute > 100, "2000 discs (2D): grid finds %d contacts, brute force %d",
                   ops->ncontacts(e), brute);
    ops->destroy(e);
    dem_test_case_free(&c);
    free(x);
    free(r);

    /* strongly polydisperse (hierarchical grid levels): 12 boulders of R 0.3-0.5 among 1500
     * grains of R 0.02-0.03 */
    const int npoly = 1512;
    dem_test_case_init(&c, 3, g0, npoly);
    m = dem_test_material(&c, "rock", LAHAR_CONTACT_LINEAR, 2500.0, 1e6, 0, 0, 0.5, 0.3);
    x = malloc(sizeof(double[3]) * npoly);
    r = malloc(sizeof(double) * npoly);
    placed = 0;
    while (placed < npoly) {
        double p[3] = {3.0 * urand(&seed), 3.0 * urand(&seed), 1.5 * urand(&seed)};
        double rad = placed < 12 ? 0.3 + 0.2 * urand(&seed) : 0.02 + 0.01 * urand(&seed);
        if (placed >= 12 && placed % 2 == 0) { /* half the grains touch a boulder (cross-level pairs) */
            int jb = placed % 12;
            double u[3] = {urand(&seed) - 0.5, urand(&seed) - 0.5, urand(&seed) - 0.5};
            double un = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]) + 1e-12;
            for (int k = 0; k < 3; k++) p[k] = x[jb][k] + u[k] / un * (r[jb] + 0.9 * rad);
        }
        int ok = 1;
        for (int j = 0; j < placed && ok; j++) {
            double dx = p[0] - x[j][0], dy = p[1] - x[j][1], dz = p[2] - x[j][2];
            double lim = rad + r[j] - 0.2 * fmin(rad, r[j]);
            if (dx * dx + dy * dy + dz * dz < lim * lim) ok = 0;
        }
        if (!ok) continue;
        memcpy(x[placed], p, sizeof p);
        r[placed] = rad;
        dem_test_sphere(&c, placed < 12 ? "boulder" : "grain", m, rad, p, LAHAR_MOTION_FREE);
        placed++;
    }
    e = dem_test_engine(&c, &ops);
    brute = count_overlaps(npoly, (const double(*)[3])x, r);
    dem_test_check(ops->ncontacts(e) == brute && brute > 300,
                   "12 boulders among 1500 grains: grid finds %d contacts, brute force %d", ops->ncontacts(e), brute);
    ops->destroy(e);
    dem_test_case_free(&c);
    free(x);
    free(r);

    /* instability */
    dem_test_case_init(&c, 3, g0, 2);
    m = dem_test_material(&c, "rock", LAHAR_CONTACT_LINEAR, 2500.0, 1e6, 0, 0, 0.5, 0.3);
    const double centre[3] = {0, 0, 0}, n[3] = {0, 0, 1}, size[2] = {3, 3}, xb[3] = {0, 0, 0.2};
    dem_test_plane(&c, "floor", m, centre, n, size, 0.02);
    int b = dem_test_sphere(&c, "cannonball", m, 0.1, xb, LAHAR_MOTION_FREE);
    c.bodies[b].v[2] = -500.0;
    e = dem_test_engine(&c, &ops);
    int rc = 0;
    for (int k = 0; k < 100 && rc >= 0; k++) rc = ops->advance(e, 1e-3, NULL, err, sizeof err);
    dem_test_check(rc == -1 && strstr(err, "cannonball") && strstr(err, "substep"), "instability reported: %s", err);
    ops->destroy(e);
    dem_test_case_free(&c);
    return dem_test_failures ? 1 : 0;
}
