/* bench_dem --lammps-data (see bench_lammps.h). The scene is the one of
 * /work/shared/bench/dem/in.time3d: monodisperse spheres, Hertz E = 1e7 Pa, nu = 0.3, mu = 0.5,
 * dt = 2e-5 s, gravity -z, frictional walls x = 0, x = xhi, y = 0, y = yhi, z = 0.
 *
 * Contact law mapping. LAMMPS gran/hertz/history: Fn = sqrt(delta R*) (kn delta - m* gn vn),
 * kn = 4G/(3(1-nu)) = 4/3 E* for equal materials, so the elastic part equals lahar's Hertz
 * k_H delta^(3/2), k_H = 4/3 E* sqrt(R*) (Canelas et al. 2015 eq. 14-16), exactly. Tangential:
 * LAMMPS kt sqrt(delta R*) xi with kt = 4G/(2-nu), i.e. lahar's kt_ratio = kt/kn = 3(1-nu)/(2-nu).
 * Damping differs in form: LAMMPS m* gn sqrt(delta R*) (~ delta^1/2), lahar alpha sqrt(m* k_H)
 * delta^(1/4) (Tsuji form, Canelas et al. 2015 eq. 15). We pick the lahar restitution whose alpha
 * gives LAMMPS's dashpot at the overlap of a sphere carrying its own weight, so the two damp a
 * resting pile alike; the kinetic-energy histories then agree within a factor (stated by the
 * caller, see tests/dem.cmake), not bit for bit. */
#include "bench_lammps.h"
#include <ctype.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "dem_contact.h"
#include "dem_engine.h"
#include "dem_test_util.h"
#ifdef LAHAR_HAVE_LAMMPS
#include <lammps/library.h>
#endif

#define BL_E 1.0e7
#define BL_NU 0.3
#define BL_MU 0.5
#define BL_GN 3.0e6
#define BL_GT 1.5e6
#define BL_GNW 1.5e6
#define BL_GTW 0.75e6
#define BL_DT 2.0e-5
#define BL_SKIN 0.001

typedef struct {
    int n;
    double lo[3], hi[3];
    double *x, *v, *w, *d, *rho; /* 3n, 3n, 3n, n, n */
} bl_data;

static void bl_free(bl_data *d)
{
    free(d->x);
    free(d->v);
    free(d->w);
    free(d->d);
    free(d->rho);
}

/* Reads `N atoms`, the box, `Atoms # sphere` (id type diameter density x y z [ix iy iz]) and
 * `Velocities` (id vx vy vz wx wy wz); atoms are stored by id (1..N). */
static int bl_read(const char *file, bl_data *d)
{
    memset(d, 0, sizeof *d);
    FILE *f = fopen(file, "r");
    if (!f) {
        fprintf(stderr, "bench_dem: cannot open the LAMMPS data file %s\n", file);
        return -1;
    }
    char line[1024];
    int section = 0, lineno = 0, got = 0, gotv = 0;
    while (fgets(line, sizeof line, f)) {
        lineno++;
        double a, b;
        long id;
        int type;
        if (lineno == 1) continue; /* title */
        if (strspn(line, " \t\r\n") == strlen(line)) continue;
        if (!strncmp(line, "Atoms", 5)) {
            if (!strstr(line, "sphere")) {
                fprintf(stderr, "%s:%d: Atoms section is not atom_style sphere (write_data of atom_style sphere)\n", file, lineno);
                fclose(f);
                return -1;
            }
            section = 1;
            continue;
        }
        if (!strncmp(line, "Velocities", 10)) {
            section = 2;
            continue;
        }
        if (isalpha((unsigned char)line[strspn(line, " \t")])) {
            section = 3; /* another section (Pair Coeffs ...): skipped */
            continue;
        }
        if (section == 0) {
            long n;
            if (sscanf(line, "%ld atoms", &n) == 1 && strstr(line, "atoms")) {
                d->n = (int)n;
                d->x = calloc(3 * (size_t)n, sizeof(double));
                d->v = calloc(3 * (size_t)n, sizeof(double));
                d->w = calloc(3 * (size_t)n, sizeof(double));
                d->d = calloc((size_t)n, sizeof(double));
                d->rho = calloc((size_t)n, sizeof(double));
                if (!d->x || !d->v || !d->w || !d->d || !d->rho) {
                    fclose(f);
                    return -1;
                }
            } else if (sscanf(line, "%lf %lf", &a, &b) == 2) {
                int ax = strstr(line, "xlo") ? 0 : strstr(line, "ylo") ? 1 : strstr(line, "zlo") ? 2 : -1;
                if (ax >= 0) {
                    d->lo[ax] = a;
                    d->hi[ax] = b;
                }
            }
            continue;
        }
        if (section == 1) {
            double dia, rho, x[3];
            if (sscanf(line, "%ld %d %lf %lf %lf %lf %lf", &id, &type, &dia, &rho, &x[0], &x[1], &x[2]) != 7 || id < 1 ||
                id > d->n || !(dia > 0.0) || !(rho > 0.0)) {
                fprintf(stderr, "%s:%d: Atoms line: expected 'id type diameter density x y z ix iy iz' with 1 <= id <= %d and diameter, density > 0\n",
                        file, lineno, d->n);
                fclose(f);
                return -1;
            }
            d->d[id - 1] = dia;
            d->rho[id - 1] = rho;
            memcpy(&d->x[3 * (id - 1)], x, sizeof x);
            got++;
        } else if (section == 2) {
            double u[6];
            if (sscanf(line, "%ld %lf %lf %lf %lf %lf %lf", &id, &u[0], &u[1], &u[2], &u[3], &u[4], &u[5]) != 7 || id < 1 ||
                id > d->n) {
                fprintf(stderr, "%s:%d: Velocities line: expected 'id vx vy vz wx wy wz' with 1 <= id <= %d\n", file, lineno, d->n);
                fclose(f);
                return -1;
            }
            memcpy(&d->v[3 * (id - 1)], u, 3 * sizeof(double));
            memcpy(&d->w[3 * (id - 1)], u + 3, 3 * sizeof(double));
            gotv++;
        }
    }
    fclose(f);
    if (d->n <= 0 || got != d->n) {
        fprintf(stderr, "%s: %d atoms declared, %d Atoms lines read (need '<N> atoms' and one line per atom)\n", file, d->n, got);
        return -1;
    }
    if (gotv != 0 && gotv != d->n) fprintf(stderr, "%s: only %d of %d atoms have velocities (others at rest)\n", file, gotv, d->n);
    return 0;
}

/* lahar restitution whose Tsuji alpha matches LAMMPS's dashpot at the resting overlap (header). */
static double bl_restitution(double dia, double rho)
{
    double r = 0.5 * dia, m = 4.0 / 3.0 * M_PI * r * r * r * rho, mstar = 0.5 * m, rstar = 0.5 * r;
    double estar = BL_E / (2.0 * (1.0 - BL_NU * BL_NU)), kn = 4.0 / 3.0 * estar;
    double delta = pow(m * 9.81 / (kn * sqrt(rstar)), 2.0 / 3.0);
    /* m* gn sqrt(delta R*) = alpha sqrt(m* kn sqrt(R*)) delta^(1/4) */
    double alpha = mstar * BL_GN * sqrt(delta * rstar) / (sqrt(mstar * kn * sqrt(rstar)) * pow(delta, 0.25));
    return dem_restitution_clipped(LAHAR_CONTACT_HERTZ, alpha);
}

static void bl_case(const bl_data *d, lahar_case *c, double e)
{
    const double g[3] = {0.0, 0.0, -9.81};
    dem_test_case_init(c, 3, g, d->n + 5);
    int m = dem_test_material(c, "glass", LAHAR_CONTACT_HERTZ, d->rho[0], 0.0, BL_E, BL_NU, e, BL_MU);
    c->materials[m].kt_ratio = 3.0 * (1.0 - BL_NU) / (2.0 - BL_NU);
    for (int i = 0; i < d->n; i++) {
        char name[24];
        snprintf(name, sizeof name, "s%d", i + 1);
        int b = dem_test_sphere(c, name, m, 0.5 * d->d[i], &d->x[3 * i], LAHAR_MOTION_FREE);
        memcpy(c->bodies[b].v, &d->v[3 * i], 3 * sizeof(double));
        memcpy(c->bodies[b].w, &d->w[3 * i], 3 * sizeof(double));
    }
    /* walls: one-sided planes whose swept surface (core + r along the normal) is the LAMMPS wall;
     * 5 cm larger than the box on every side, so no sphere reaches their rims */
    const double r = 1e-3, pad = 0.05;
    double lx = d->hi[0] - d->lo[0], ly = d->hi[1] - d->lo[1], hz = d->hi[2] + pad;
    double cx = 0.5 * (d->lo[0] + d->hi[0]), cy = 0.5 * (d->lo[1] + d->hi[1]);
    const double up[3] = {0, 0, 1}, fc[3] = {cx, cy, -r}, fs[2] = {lx + 2 * pad, ly + 2 * pad};
    dem_test_plane(c, "zlo", m, fc, up, fs, r);
    for (int k = 0; k < 4; k++) {
        int ax = k / 2, hi = k % 2;
        double n[3] = {0, 0, 0}, cen[3] = {cx, cy, 0.5 * hz - pad};
        n[ax] = hi ? -1.0 : 1.0;
        cen[ax] = hi ? d->hi[ax] + r : d->lo[ax] - r;
        double sz[2] = {(ax == 0 ? ly : lx) + 2 * pad, hz + pad};
        char name[8];
        snprintf(name, sizeof name, "%clo", ax == 0 ? 'x' : 'y');
        if (hi) name[1] = 'h', name[2] = 'i';
        dem_test_plane(c, name, m, cen, n, sz, r);
    }
}

static int cmp_x(const void *a, const void *b)
{
    double u = **(const double *const *)a, w = **(const double *const *)b;
    return (u > w) - (u < w);
}

/* Sphere-sphere contacts (centre distance < sum of radii) of n spheres, counted the same way for
 * both codes: sort by x, sweep. */
static long bl_contacts(int n, const double *x, const double *rad, double rmax)
{
    const double **p = malloc(sizeof *p * (size_t)n);
    if (!p) return -1;
    for (int i = 0; i < n; i++) p[i] = &x[3 * i];
    qsort(p, (size_t)n, sizeof *p, cmp_x);
    long cnt = 0;
    for (int i = 0; i < n; i++) {
        long a = (p[i] - x) / 3;
        for (int j = i + 1; j < n && p[j][0] - p[i][0] < 2.0 * rmax; j++) {
            long b = (p[j] - x) / 3;
            double dx = p[j][0] - p[i][0], dy = p[j][1] - p[i][1], dz = p[j][2] - p[i][2], rs = rad[a] + rad[b];
            cnt += dx * dx + dy * dy + dz * dz < rs * rs;
        }
    }
    free(p);
    return cnt;
}

/* CPU time of the process (all its threads): on a machine shared with other jobs the wall time
 * mostly measures the waiting for a core, the CPU time what the code costs. */
static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct {
    double core_us;     /* CPU microseconds (all threads) per particle-step */
    double rate;        /* particle-steps per second of wall time */
    long contacts;      /* sphere-sphere contacts at the end */
    double ke0, ke1;    /* kinetic energy (translation + rotation) after the warm-up and at the end */
    unsigned long long digest; /* lahar: state digest at the end (equal on any thread count) */
} bl_result;

/* The timed steps, a function of its own for
 * valgrind --tool=callgrind --collect-atstart=no --toggle-collect='bench_lammps_measure*' */
static __attribute__((noinline)) int bench_lammps_measure(const lahar_dem_engine_ops *ops, lahar_dem_engine *e, int steps,
                                                          char *err, size_t errlen)
{
    for (int k = 0; k < steps; k++)
        if (ops->advance(e, BL_DT, NULL, err, errlen) != 1) return -1;
    return 0;
}

static int bl_run_lahar(const bl_data *d, const lahar_case *c, const bench_lammps_opts *o, bl_result *res)
{
    const lahar_dem_engine_ops *ops;
    omp_set_num_threads(o->threads);
    lahar_dem_engine *e = dem_test_engine(c, &ops);
    char err[512];
    if (ops->stable_dt(e) < BL_DT) {
        fprintf(stderr, "bench_dem: the engine's stable step %.3g s is below LAMMPS's %.3g s\n", ops->stable_dt(e), BL_DT);
        ops->destroy(e);
        return -1;
    }
    for (int k = 0; k < o->warm; k++)
        if (ops->advance(e, BL_DT, NULL, err, sizeof err) < 0) {
            fprintf(stderr, "bench_dem: lahar warm-up: %s\n", err);
            ops->destroy(e);
            return -1;
        }
    res->ke0 = ops->kinetic_energy(e);
    double t0 = omp_get_wtime(), c0 = cpu_seconds();
    if (bench_lammps_measure(ops, e, o->steps, err, sizeof err)) {
        fprintf(stderr, "bench_dem: lahar: %s\n", err);
        ops->destroy(e);
        return -1;
    }
    double wall = omp_get_wtime() - t0;
    res->core_us = 1e6 * (cpu_seconds() - c0) / ((double)d->n * o->steps);
    res->ke1 = ops->kinetic_energy(e);
    res->digest = dem_test_digest(ops, e);
    res->rate = (double)d->n * o->steps / wall;
    double *x = malloc(sizeof(double) * 3 * (size_t)d->n), *rad = malloc(sizeof(double) * (size_t)d->n), rmax = 0.0;
    if (!x || !rad) {
        free(x);
        free(rad);
        ops->destroy(e);
        return -1;
    }
    for (int i = 0; i < d->n; i++) {
        lahar_body_state st;
        ops->get_state(e, i, &st);
        memcpy(&x[3 * i], st.x, sizeof st.x);
        rad[i] = 0.5 * d->d[i];
        rmax = fmax(rmax, rad[i]);
    }
    res->contacts = bl_contacts(d->n, x, rad, rmax);
    free(x);
    free(rad);
    ops->destroy(e);
    return 0;
}

#ifdef LAHAR_HAVE_LAMMPS
static double bl_lammps_ke(void *lmp, int n)
{
    double **v = lammps_extract_atom(lmp, "v"), **w = lammps_extract_atom(lmp, "omega");
    double *m = lammps_extract_atom(lmp, "rmass"), *r = lammps_extract_atom(lmp, "radius");
    double k = 0.0;
    for (int i = 0; i < n; i++)
        k += 0.5 * m[i] * (v[i][0] * v[i][0] + v[i][1] * v[i][1] + v[i][2] * v[i][2]) +
             0.5 * 0.4 * m[i] * r[i] * r[i] * (w[i][0] * w[i][0] + w[i][1] * w[i][1] + w[i][2] * w[i][2]);
    return k;
}

/* The commands of in.time3d on the same data file, through the C library (1 process, 1 rank). */
static int bl_run_lammps(const bench_lammps_opts *o, bl_result *res)
{
    char *args[] = {"lammps", "-screen", "none", "-log", "none", NULL};
    void *lmp = lammps_open_no_mpi(5, args, NULL);
    if (!lmp) return -1;
    double G = BL_E / (2.0 * (1.0 + BL_NU)), kn = 4.0 * G / (3.0 * (1.0 - BL_NU)), kt = 4.0 * G / (2.0 - BL_NU);
    char cmd[1024];
    const char *fixed[] = {"units si", "atom_style sphere", "dimension 3", "boundary f f f", "comm_modify vel yes"};
    for (size_t k = 0; k < sizeof fixed / sizeof *fixed; k++) lammps_command(lmp, fixed[k]);
    snprintf(cmd, sizeof cmd, "read_data %s", o->file);
    lammps_command(lmp, cmd);
    snprintf(cmd, sizeof cmd, "pair_style gran/hertz/history %.17g %.17g %.17g %.17g %g 1", kn, kt, BL_GN, BL_GT, BL_MU);
    lammps_command(lmp, cmd);
    lammps_command(lmp, "pair_coeff * *");
    snprintf(cmd, sizeof cmd, "neighbor %g bin", BL_SKIN);
    lammps_command(lmp, cmd);
    lammps_command(lmp, "neigh_modify delay 0 every 1 check yes");
    snprintf(cmd, sizeof cmd, "timestep %g", BL_DT);
    lammps_command(lmp, cmd);
    lammps_command(lmp, "fix integ all nve/sphere");
    lammps_command(lmp, "fix grav all gravity 9.81 vector 0 0 -1");
    const char *wall[3] = {"wx", "wy", "wz"}, *pl[3] = {"xplane 0 ${L}", "yplane 0 ${L}", "zplane 0 NULL"};
    lammps_command(lmp, "variable L equal xhi");
    for (int k = 0; k < 3; k++) {
        snprintf(cmd, sizeof cmd, "fix %s all wall/gran hertz/history %.17g %.17g %.17g %.17g %g 1 %s", wall[k], kn, kt,
                 BL_GNW, BL_GTW, BL_MU, pl[k]);
        lammps_command(lmp, cmd);
    }
    int n = (int)lammps_get_natoms(lmp);
    int rc = 0;
    if (n <= 0) rc = -1;
    if (rc == 0) {
        snprintf(cmd, sizeof cmd, "run %d", o->warm);
        if (o->warm > 0) lammps_command(lmp, cmd);
        res->ke0 = bl_lammps_ke(lmp, n);
        snprintf(cmd, sizeof cmd, "run %d", o->steps);
        double t0 = omp_get_wtime(), c0 = cpu_seconds();
        lammps_command(lmp, cmd);
        double wall_t = omp_get_wtime() - t0;
        res->core_us = 1e6 * (cpu_seconds() - c0) / ((double)n * o->steps);
        res->rate = (double)n * o->steps / wall_t;
        res->ke1 = bl_lammps_ke(lmp, n);
        double **x = lammps_extract_atom(lmp, "x"), *r = lammps_extract_atom(lmp, "radius"), rmax = 0.0;
        double *xf = malloc(sizeof(double) * 3 * (size_t)n);
        if (!xf) rc = -1;
        else {
            for (int i = 0; i < n; i++) {
                memcpy(&xf[3 * i], x[i], 3 * sizeof(double));
                rmax = fmax(rmax, r[i]);
            }
            res->contacts = bl_contacts(n, xf, r, rmax);
            free(xf);
        }
    }
    lammps_close(lmp);
    return rc;
}
#endif

int bench_lammps_run(const bench_lammps_opts *o)
{
    bl_data d;
    if (bl_read(o->file, &d)) {
        bl_free(&d);
        return 2;
    }
    lahar_case c;
    double e = bl_restitution(d.d[0], d.rho[0]);
    bl_case(&d, &c, e);
    printf("# %s: %d spheres, %d warm-up + %d timed steps of %g s; lahar restitution %.4f (dashpot matched to LAMMPS gn)\n",
           o->file, d.n, o->warm, o->steps, BL_DT, e);
    printf("| code | threads | particle-steps/s (wall) | core-us per particle-step (CPU time) | sphere-sphere contacts per sphere | KE after warm-up (J) | KE at end (J) |\n");
    printf("|---|---|---|---|---|---|---|\n");
    bl_result lh = {0}, lm = {0};
    int rc = 0, have_lmp = 0, have_lahar = 0;
    if (bl_run_lahar(&d, &c, o, &lh)) rc = 2;
    else have_lahar = 1;
    if (have_lahar)
        printf("| lahar spheropoly | %d | %.3g | %.4f | %.3f | %.4e | %.4e |\n", o->threads, lh.rate, lh.core_us,
               (double)lh.contacts / d.n, lh.ke0, lh.ke1);
    fflush(stdout);
#ifdef LAHAR_HAVE_LAMMPS
    if (o->lammps && rc == 0) {
        if (bl_run_lammps(o, &lm)) rc = 2;
        else {
            have_lmp = 1;
            printf("| LAMMPS gran/hertz/history (library) | 1 | %.3g | %.4f | %.3f | %.4e | %.4e |\n", lm.rate, lm.core_us,
                   (double)lm.contacts / d.n, lm.ke0, lm.ke1);
            printf("\nlahar/LAMMPS: speed per core (CPU time) %.3f, wall-time speed %.3f, contacts %.4f, KE at end %.3f\n",
                   lm.core_us / lh.core_us, lh.rate / lm.rate, (double)lh.contacts / (double)lm.contacts, lh.ke1 / lm.ke1);
        }
    }
#else
    if (o->lammps) printf("\n(LAMMPS comparison not built: liblammps-dev was not found at configure time)\n");
#endif
    if (rc == 0 && have_lmp) {
        if (o->contact_tol > 0.0) {
            double rel = fabs((double)lh.contacts - (double)lm.contacts) / (double)lm.contacts;
            printf("%s: contacts lahar %ld, LAMMPS %ld, relative difference %.3g (tolerance %g)\n",
                   rel <= o->contact_tol ? "ok  " : "FAIL", lh.contacts, lm.contacts, rel, o->contact_tol);
            if (rel > o->contact_tol) rc = 1;
        }
        if (o->ke_tol > 0.0) {
            double lr = fabs(log(lh.ke1 / lm.ke1)), lr0 = fabs(log(lh.ke0 / lm.ke0));
            int ok = lr <= log(o->ke_tol) && lr0 <= log(o->ke_tol) && lh.ke1 < lh.ke0 && lm.ke1 < lm.ke0;
            printf("%s: KE decay lahar %.4e -> %.4e J, LAMMPS %.4e -> %.4e J (both must fall and agree within x%g)\n",
                   ok ? "ok  " : "FAIL", lh.ke0, lh.ke1, lm.ke0, lm.ke1, o->ke_tol);
            if (!ok) rc = 1;
        }
    }
    if (have_lahar) printf("lahar state digest at the end: %016llx (%d threads)\n", lh.digest, o->threads);
    dem_test_case_free(&c);
    bl_free(&d);
    return rc;
}
