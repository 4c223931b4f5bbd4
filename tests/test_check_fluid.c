/* `lahar check` references of the SPH cases on synthetic runs written through the real output
 * writers (particles.h5, bodies.h5, forces.h5). Each reference gets the exact analytic fields
 * (must pass, error at rounding level) and a perturbed run (must fail with the error the
 * perturbation implies):
 *  - the Poiseuille series itself against a Crank-Nicolson solution of u_t = nu u_yy + a and its
 *    wall stress against a finite difference of the series;
 *  - poiseuille: H = 0.1, a = 1e-4, rho = 1000, mu = 0.1 (Trujillo-Vela et al. 2020 section 5.1), 20 particles
 *    across; velocity x 1.02 -> steady_l2_rel_error 0.02; plate force x 1.03 -> 0.03;
 *  - cylinder_array: c = 0.1 (K = 24.83), uniform velocity giving U_s exactly; U x 1.06 fails;
 *    the table's interpolation and low-c asymptote (7.981 at c = 0.01);
 *  - sphere_array: Zick & Homsy's table, its interpolation and the dilute series (lookup only);
 *  - hydrostatic: 2D tank, h = 0.3 m, p = rho g (h - y), wall forces rho g h^2/2; wall force
 *    x 1.02 and pressure x 1.05 fail; 3D tank of planes (wetted widths per wall), a wall at 0.97
 *    fails. The level gauges read a lattice's top row + dx/2 within LATTICE_LEVEL dx (kernel.h),
 *    so the depth is exact within that and the relative errors within 2 LATTICE_LEVEL dx / h;
 *    a surface particle missing or raised moves the gauges' spread by less than the column's
 *    top particle would;
 *  - floating_box: box 0.2 x 0.1 m, density 500 -> draft 0.05 m; raised 2 mm -> error 0.04;
 *  - sinking_disc: a disc settles on the floor; a particle inside the floor's layer fails;
 *  - dam_break: a column spreading to the far wall; a particle out of the tank, one deep inside a
 *    fixed box's core, one in the sweep of a 79-feature ledge (the feature-grid path) and a front
 *    that steps back fail;
 *  - dam_break against Martin & Moyce 1952 (n^2 = 2): a front on their data passes, 10 % ahead
 *    gives front_rel_error 0.1;
 *  - missing particles / fields -> status 2.
 *   test_check_fluid OUTDIR */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include "check.h"
#include "output.h"
#include "shape_build.h"
#include "vec.h"

#include "test_util.h"

#define MAXP 20000
#define MAXB 6
static double px[MAXP], py[MAXP], pz[MAXP], pvx[MAXP], pvy[MAXP], pden[MAXP], ppr[MAXP];
static int64_t np;
static lahar_material mats[2];
static lahar_body bodies[MAXB];
static int nbodies;
static lahar_case cs;
static lahar_body_state states[MAXB];
static lahar_body_report reports[MAXB];

/* ---------------------------------------------------------------- case set-up ----------- */

/* How far the level gauges' surface (kernel volume fraction 1/2) may lie from a lattice's top row
 * + dx/2, in dx: 2e-4 (2D) and 6e-4 (3D) measured for the cubic kernel, h = 1.3 dx. */
#define LATTICE_LEVEL 1e-3

static void case_begin(const char *ref, int dim)
{
    for (int i = 0; i < nbodies; i++)
        lahar_shape_free(&bodies[i].shape);
    memset(bodies, 0, sizeof bodies);
    memset(&cs, 0, sizeof cs);
    memset(mats, 0, sizeof mats);
    nbodies = 0;
    memset(pz, 0, sizeof pz);
    snprintf(mats[0].name, sizeof mats[0].name, "wall");
    mats[0].density = 2000, mats[0].restitution = 0.5, mats[0].friction = 0.5, mats[0].kn = 1e6;
    snprintf(mats[1].name, sizeof mats[1].name, "light");
    mats[1].density = 500, mats[1].restitution = 0.5, mats[1].friction = 0.5, mats[1].kn = 1e6;
    snprintf(cs.path, sizeof cs.path, "synthetic_%s.yaml", ref);
    cs.dim = dim, cs.gravity[dim - 1] = -9.81, cs.output_interval = 0.1, cs.output_forces = 1;
    cs.output_fields = LAHAR_PFIELD_ALL;
    cs.nmaterial = 2, cs.materials = mats, cs.bodies = bodies;
    cs.sph_density = 1000.0;
    cs.sph.mu = 1e-3;
    snprintf(cs.sph.kernel, sizeof cs.sph.kernel, "cubic"), cs.sph.h_over_dx = 1.3;
    cs.check.enabled = 1;
    snprintf(cs.check.reference, sizeof cs.check.reference, "%s", ref);
}

static void metric(const char *name, double bound)
{
    snprintf(cs.check.metric[cs.check.nmetric].name, LAHAR_NAME_MAX, "%s", name);
    cs.check.metric[cs.check.nmetric].bound = bound;
    cs.check.nmetric++;
}

static int add_body(const char *name, lahar_motion motion, int mat)
{
    lahar_body *b = &bodies[nbodies];
    snprintf(b->name, sizeof b->name, "%s", name);
    b->motion = motion, b->material = mat, b->q[0] = 1.0, b->convex = 1;
    cs.nbody = ++nbodies;
    return nbodies - 1;
}

/* A fixed 2D wall: segment a-b swept by R. */
static int add_segment(const char *name, double ax, double ay, double bx, double by, double R)
{
    int j = add_body(name, LAHAR_MOTION_FIXED, 0);
    double a[3] = {ax, ay, 0}, b[3] = {bx, by, 0};
    lahar_shape_make_segment(&bodies[j].shape, a, b, R);
    return j;
}

/* ---------------------------------------------------------------- writing a run --------- */

typedef struct {
    lahar_body_output *bo;
    lahar_particle_output *po;
} run_out;

static int run_open(const char *dir, run_out *o)
{
    char err[512];
    mkdir(dir, 0755);
    o->bo = lahar_body_output_open(dir, &cs, err, sizeof err);
    CHECK(o->bo, "body output: %s", err);
    o->po = lahar_particle_output_open(dir, &cs, cs.output_fields, err, sizeof err);
    CHECK(o->po, "particle output: %s", err);
    return o->bo && o->po ? 0 : -1;
}

/* Snapshot of bodies (states[]) and particles (px.. arrays) at step k, time t. */
static void run_snapshot(run_out *o, int64_t k, double t)
{
    for (int j = 0; j < nbodies; j++)
        if (bodies[j].motion == LAHAR_MOTION_FIXED) {
            memcpy(states[j].x, bodies[j].x, sizeof states[j].x);
            memcpy(states[j].q, bodies[j].q, sizeof states[j].q);
        }
    CHECK(lahar_body_output_snapshot(o->bo, k, t, states) == 0, "body snapshot");
    lahar_particles_view v = {np, px, py, pz, pvx, pvy, NULL, pden, ppr, NULL, NULL, {NULL}, NULL, NULL};
    static double zeros[MAXP];
    static int32_t phase[MAXP];
    static int64_t ids[MAXP];
    for (int64_t i = 0; i < np; i++)
        ids[i] = i;
    v.vz = zeros, v.phase = phase, v.id = ids;
    CHECK(lahar_particle_output_snapshot(o->po, k, t, &v) == 0, "particle snapshot");
}

static void run_close(run_out *o)
{
    lahar_particle_output_close(o->po);
    lahar_body_output_close(o->bo);
}

/* ---------------------------------------------------------------- check.json ------------ */

static double json_metric(const char *dir, const char *name, int *pass)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/check.json", dir);
    FILE *f = fopen(path, "r");
    if (!f)
        return NAN;
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = malloc((size_t)len + 1);
    size_t n = buf ? fread(buf, 1, (size_t)len, f) : 0;
    fclose(f);
    if (!buf)
        return NAN;
    buf[n] = 0;
    cJSON *root = cJSON_Parse(buf);
    free(buf);
    double v = NAN;
    if (root) {
        cJSON *m = cJSON_GetObjectItem(cJSON_GetObjectItem(root, "metrics"), name);
        if (!m)
            m = cJSON_GetObjectItem(root, "info") ? cJSON_GetObjectItem(cJSON_GetObjectItem(root, "info"), name) : NULL;
        cJSON *val = m && cJSON_IsObject(m) ? cJSON_GetObjectItem(m, "value") : m;
        if (cJSON_IsNumber(val))
            v = val->valuedouble;
        if (pass)
            *pass = cJSON_IsTrue(cJSON_GetObjectItem(root, "pass"));
        cJSON_Delete(root);
    }
    return v;
}

/* Evaluate dir; expect status `want`; return the value of `name` (metrics or info). */
static double evaluate(const char *dir, int want, const char *name)
{
    /* the plot of every passing run (python3 + matplotlib), none for the others (time) */
    char png[1200];
    snprintf(png, sizeof png, "%s/check.png", dir);
    if (want == 0)
        unlink(png);
    setenv("LAHAR_CHECK_NO_PLOT", want == 0 ? "0" : "1", 1);
    int rc = lahar_check_evaluate(&cs, dir);
    CHECK(rc == want, "%s: lahar check status %d, expected %d", dir, rc, want);
    if (want == 0)
        CHECK(access(png, R_OK) == 0, "no %s (python3 + matplotlib needed)", png);
    int pass = -1;
    double v = json_metric(dir, name, &pass);
    if (want != 2)
        CHECK(pass == (want == 0), "%s: check.json pass = %d", dir, pass);
    return v;
}

/* ---------------------------------------------------------------- poiseuille ------------ */

static const double PH = 0.1, PA = 1e-4, PRHO = 1000.0, PMU = 0.1, PL = 0.05;

/* Crank-Nicolson for u_t = nu u_yy + a, u(0) = u(H) = 0, u(y, 0) = 0: an independent check of the
 * series (it is the reference of the evaluator). */
static void poiseuille_series_vs_cn(void)
{
    enum { N = 400 };
    const double nu = PMU / PRHO, dy = PH / N, t_end = 8.0, dt = 2e-3;
    static double u[N + 1], rhs[N + 1], cp[N + 1], dp[N + 1];
    memset(u, 0, sizeof u);
    double r = nu * dt / (dy * dy);
    int steps = (int)lround(t_end / dt);
    for (int s = 0; s < steps; s++) {
        for (int i = 1; i < N; i++)
            rhs[i] = u[i] + 0.5 * r * (u[i - 1] - 2.0 * u[i] + u[i + 1]) + dt * PA;
        /* Thomas algorithm for -r/2 u[i-1] + (1 + r) u[i] - r/2 u[i+1] = rhs[i] */
        double a = -0.5 * r, b = 1.0 + r;
        cp[1] = a / b, dp[1] = rhs[1] / b;
        for (int i = 2; i < N; i++) {
            double m = b - a * cp[i - 1];
            cp[i] = a / m, dp[i] = (rhs[i] - a * dp[i - 1]) / m;
        }
        u[N - 1] = dp[N - 1];
        for (int i = N - 2; i >= 1; i--)
            u[i] = dp[i] - cp[i] * u[i + 1];
    }
    double umax = PA * PH * PH / (8.0 * nu), err = 0.0;
    for (int i = 0; i <= N; i++)
        err = fmax(err, fabs(u[i] - lahar_check_poiseuille_u(i * dy, t_end, PH, PA, nu)));
    CHECK(err < 1e-4 * umax, "series vs Crank-Nicolson at t = %g: max error %g of u_max %g", t_end, err, umax);
    CHECK(fabs(lahar_check_poiseuille_u(0.5 * PH, 1e4, PH, PA, nu) - umax) < 1e-12 * umax, "steady u_max");
    /* wall stress = rho nu du/dy at y = 0 (one-sided 4th-order difference of the series) */
    for (double t = 0.5; t < 100.0; t *= 4.0) {
        double h = 1e-4 * PH, f[5];
        for (int i = 0; i < 5; i++)
            f[i] = lahar_check_poiseuille_u(i * h, t, PH, PA, nu);
        double dudy = (-25.0 * f[0] + 48.0 * f[1] - 36.0 * f[2] + 16.0 * f[3] - 3.0 * f[4]) / (12.0 * h);
        double tau = lahar_check_poiseuille_wall_stress(t, PH, PA, nu, PRHO), tau_s = PRHO * PA * PH / 2.0;
        CHECK(fabs(PRHO * nu * dudy - tau) < 1e-6 * tau_s, "wall stress at t = %g: %g vs rho nu du/dy %g", t, tau,
              PRHO * nu * dudy);
    }
    CHECK(fabs(lahar_check_poiseuille_wall_stress(1e4, PH, PA, nu, PRHO) - PRHO * PA * PH / 2.0) < 1e-12,
          "steady wall stress rho a H / 2");
}

static void poiseuille_run(const char *dir, double ufac, double ffac)
{
    case_begin("poiseuille", 2);
    cs.gravity[1] = 0.0;
    cs.sph.body_force[0] = PA;
    cs.sph_density = PRHO, cs.sph.mu = PMU;
    const double dx = PH / 20.0, R = 0.002, nu = PMU / PRHO;
    cs.sph_dx = dx;
    cs.sph.periodic[0] = 1, cs.sph.lo[0] = 0.0, cs.sph.hi[0] = PL;
    int lo = add_segment("bottom", -0.1, -R, 0.15, -R, R);
    int hi = add_segment("top", -0.1, PH + R, 0.15, PH + R, R);
    metric("steady_l2_rel_error", 0.01);
    metric("plate_force_rel_error", 0.01);
    run_out o;
    if (run_open(dir, &o))
        return;
    const double ts[] = {0.0, 5.0, 10.0, 20.0, 40.0, 80.0, 160.0};
    int isnap = 0;
    for (int step = 0; step <= 160; step++) {
        double t = step;
        memset(reports, 0, sizeof reports);
        double f = lahar_check_poiseuille_wall_stress(t, PH, PA, nu, PRHO) * PL * ffac;
        reports[lo].force[0] = reports[hi].force[0] = f;
        reports[lo].ncontacts = reports[hi].ncontacts = 10;
        lahar_body_output_forces(o.bo, step, t, reports);
        if (isnap < 7 && t == ts[isnap]) {
            np = 0;
            for (int i = 0; i < 10; i++)
                for (int j = 0; j < 20; j++, np++) {
                    px[np] = (i + 0.5) * dx, py[np] = (j + 0.5) * dx;
                    pvx[np] = ufac * lahar_check_poiseuille_u(py[np], t, PH, PA, nu), pvy[np] = 0.0;
                    pden[np] = PRHO, ppr[np] = 0.0;
                }
            run_snapshot(&o, step, t);
            isnap++;
        }
    }
    run_close(&o);
}

static void test_poiseuille(const char *base)
{
    char dir[1100];
    poiseuille_series_vs_cn();
    snprintf(dir, sizeof dir, "%s/poiseuille_pass", base);
    poiseuille_run(dir, 1.0, 1.0);
    double v = evaluate(dir, 0, "steady_l2_rel_error");
    CHECK(v < 1e-9, "poiseuille exact: steady_l2_rel_error %g", v);
    v = json_metric(dir, "plate_force_rel_error", NULL);
    CHECK(v < 1e-6, "poiseuille exact: plate_force_rel_error %g", v);
    v = json_metric(dir, "H", NULL);
    CHECK(fabs(v - PH) < 1e-12, "poiseuille: H from the plates %g", v);
    v = json_metric(dir, "transient_l2_rel_error_max", NULL);
    CHECK(v < 1e-9, "poiseuille exact: transient_l2_rel_error_max %g", v);

    snprintf(dir, sizeof dir, "%s/poiseuille_slow", base);
    poiseuille_run(dir, 1.02, 1.0);
    v = evaluate(dir, 1, "steady_l2_rel_error");
    CHECK(fabs(v - 0.02) < 1e-9, "poiseuille u x 1.02: steady_l2_rel_error %.12g (expected 0.02)", v);

    snprintf(dir, sizeof dir, "%s/poiseuille_force", base);
    poiseuille_run(dir, 1.0, 1.03);
    v = evaluate(dir, 1, "plate_force_rel_error");
    CHECK(fabs(v - 0.03) < 1e-4, "poiseuille force x 1.03: plate_force_rel_error %.8g (expected 0.03)", v);
}

/* ---------------------------------------------------------------- cylinder array -------- */

static void cylinder_run(const char *dir, double conc, double ufac)
{
    case_begin("cylinder_array", 2);
    const double L = 0.2, g = 2e-5, mu = 0.1, rho = 1000.0, dx = L / 50.0;
    cs.gravity[1] = 0.0;
    cs.sph.body_force[0] = g;
    cs.sph.mu = mu, cs.sph_density = rho, cs.sph_dx = dx;
    for (int a = 0; a < 2; a++)
        cs.sph.periodic[a] = 1, cs.sph.lo[a] = 0.0, cs.sph.hi[a] = L;
    int disc = add_body("cylinder", LAHAR_MOTION_FIXED, 0);
    double r = sqrt(conc * L * L / M_PI);
    lahar_shape_make_sphere(&bodies[disc].shape, r);
    bodies[disc].x[0] = bodies[disc].x[1] = 0.5 * L;
    metric("K_rel_error", 0.05);
    run_out o;
    if (run_open(dir, &o))
        return;
    double Us = rho * g * L * L / (mu * lahar_check_sangani_acrivos_K(conc));
    for (int k = 0; k <= 5; k++) {
        double t = 100.0 * k;
        np = 0;
        for (int i = 0; i < 50; i++)
            for (int j = 0; j < 50; j++) {
                double x = (i + 0.5) * dx, y = (j + 0.5) * dx;
                if (hypot(x - 0.5 * L, y - 0.5 * L) < r + 0.5 * dx)
                    continue;
                px[np] = x, py[np] = y, pvx[np] = ufac * Us / (1.0 - conc), pvy[np] = 0.0;
                pden[np] = rho, ppr[np] = 0.0;
                np++;
            }
        memset(reports, 0, sizeof reports);
        reports[disc].force[0] = rho * g * (1.0 - conc) * L * L;
        lahar_body_output_forces(o.bo, k, t, reports);
        run_snapshot(&o, k, t);
    }
    run_close(&o);
}

static void test_cylinder(const char *base)
{
    char dir[1100];
    CHECK(fabs(lahar_check_sangani_acrivos_K(0.1) - 24.83) < 1e-12, "SA table at 0.1");
    CHECK(fabs(lahar_check_sangani_acrivos_K(0.15) - sqrt(24.83 * 51.53)) < 1e-9, "SA ln K interpolation at 0.15");
    CHECK(fabs(lahar_check_sangani_acrivos_K(0.01) - 7.981) < 1e-3, "SA low-c asymptote at 0.01: %g (ref 7.981)",
          lahar_check_sangani_acrivos_K(0.01));
    CHECK(fabs(lahar_check_sangani_acrivos_K(0.0499999) / 15.56 - 1.0) < 1e-3,
          "SA asymptote meets the table at 0.05: %g", lahar_check_sangani_acrivos_K(0.0499999));
    CHECK(isnan(lahar_check_sangani_acrivos_K(0.8)), "SA beyond close packing is NAN");
    /* Zick & Homsy (1982) Table 2, simple cubic (cases/sphere_array_reference.md) */
    CHECK(fabs(lahar_check_zick_homsy_K(0.064) - 2.810) < 1e-12, "ZH table at 0.064");
    CHECK(fabs(lahar_check_zick_homsy_K(0.216) - 7.442) < 1e-12, "ZH table at 0.216");
    CHECK(fabs(lahar_check_zick_homsy_K(0.1705) - sqrt(4.292 * 7.442)) < 1e-9, "ZH ln K interpolation at 0.1705");
    CHECK(fabs(lahar_check_zick_homsy_K(0.008) - 1.5247) < 1e-4, "ZH dilute series at 0.008: %g (ref 1.5247)",
          lahar_check_zick_homsy_K(0.008));
    CHECK(fabs(lahar_check_zick_homsy_K(0.0269999) / 2.008 - 1.0) < 1e-3, "dilute series meets ZH at 0.027: %g",
          lahar_check_zick_homsy_K(0.0269999));
    CHECK(isnan(lahar_check_zick_homsy_K(0.53)), "ZH beyond close packing is NAN");

    snprintf(dir, sizeof dir, "%s/cylinder_pass", base);
    cylinder_run(dir, 0.1, 1.0);
    double v = evaluate(dir, 0, "K_rel_error");
    CHECK(v < 1e-9, "cylinder exact: K_rel_error %g", v);
    v = json_metric(dir, "force_balance_rel_error", NULL);
    CHECK(v < 1e-9, "cylinder: force_balance_rel_error %g", v);

    snprintf(dir, sizeof dir, "%s/cylinder_fast", base);
    cylinder_run(dir, 0.2, 1.06);
    v = evaluate(dir, 1, "K_rel_error");
    CHECK(fabs(v - (1.0 - 1.0 / 1.06)) < 1e-9, "cylinder U x 1.06: K_rel_error %.10g (expected %.10g)", v,
          1.0 - 1.0 / 1.06);
}

/* ---------------------------------------------------------------- hydrostatic ----------- */

/* defect: 0 a lattice; 1 the top particle of column 20 missing; 2 raised by dx/2 */
static void hydro_run(const char *dir, double ffac, double pfac, int defect)
{
    case_begin("hydrostatic", 2);
    const double W = 0.4, h = 0.3, dx = 0.01, R = 0.002, rho = 1000.0, g = 9.81;
    cs.sph_dx = dx;
    int fl = add_segment("floor", -0.05, -R, W + 0.05, -R, R);
    int left = add_segment("left", -R, 0.0, -R, 0.6, R);
    int right = add_segment("right", W + R, 0.0, W + R, 0.6, R);
    metric("wall_force_rel_error", 0.01);
    metric("pressure_l2_rel_error", 0.02);
    run_out o;
    if (run_open(dir, &o))
        return;
    for (int k = 0; k <= 10; k++) {
        double t = 0.1 * k;
        np = 0;
        for (int i = 0; i < 40; i++)
            for (int j = 0; j < 30; j++) {
                if (defect == 1 && i == 20 && j == 29)
                    continue;
                px[np] = (i + 0.5) * dx, py[np] = (j + 0.5 + (defect == 2 && i == 20 && j == 29 ? 0.5 : 0.0)) * dx;
                pvx[np] = pvy[np] = 0.0, ppr[np] = pfac * rho * g * (h - py[np]), pden[np] = rho;
                np++;
            }
        memset(reports, 0, sizeof reports);
        reports[fl].force[1] = -rho * g * h * W;
        reports[left].force[0] = -0.5 * rho * g * h * h * ffac;
        reports[right].force[0] = 0.5 * rho * g * h * h;
        lahar_body_output_forces(o.bo, k, t, reports);
        run_snapshot(&o, k, t);
    }
    run_close(&o);
}

static void test_hydrostatic(const char *base)
{
    char dir[1100];
    snprintf(dir, sizeof dir, "%s/hydro_pass", base);
    hydro_run(dir, 1.0, 1.0, 0);
    const double tol = 2.0 * LATTICE_LEVEL * 0.01 / 0.3; /* dx 0.01, h 0.3 */
    double v = evaluate(dir, 0, "wall_force_rel_error");
    CHECK(v < tol, "hydrostatic exact: wall_force_rel_error %g (< %g)", v, tol);
    v = json_metric(dir, "pressure_l2_rel_error", NULL);
    CHECK(v < tol, "hydrostatic exact: pressure_l2_rel_error %g (< %g)", v, tol);
    v = json_metric(dir, "depth", NULL);
    CHECK(fabs(v - 0.3) < LATTICE_LEVEL * 0.01, "hydrostatic: depth %.9g (0.3)", v);
    v = json_metric(dir, "free_surface_spread_rel", NULL);
    CHECK(v < tol, "hydrostatic: free_surface_spread_rel %g on a lattice (< %g)", v, tol);
    v = json_metric(dir, "side_walls", NULL);
    CHECK(v == 2.0, "hydrostatic: %g side walls (2)", v);

    snprintf(dir, sizeof dir, "%s/hydro_wall", base);
    hydro_run(dir, 1.02, 1.0, 0);
    v = evaluate(dir, 1, "wall_force_rel_error");
    CHECK(fabs(v - 0.02) < tol, "hydrostatic wall x 1.02: wall_force_rel_error %.10g", v);

    snprintf(dir, sizeof dir, "%s/hydro_pressure", base);
    hydro_run(dir, 1.0, 1.05, 0);
    v = evaluate(dir, 1, "pressure_l2_rel_error");
    CHECK(fabs(v - 0.05) < tol, "hydrostatic p x 1.05: pressure_l2_rel_error %.10g", v);
    /* one surface particle missing or raised by dx/2: the gauges' spread (0.51 dx, 0.12 dx) stays
     * below what the column's top particle shows (1 dx, 0.5 dx), the mean depth within dx/20 */
    const double spread_max[3] = {0.0, 0.6, 0.2};
    for (int defect = 1; defect <= 2; defect++) {
        snprintf(dir, sizeof dir, "%s/hydro_defect%d", base, defect);
        hydro_run(dir, 1.0, 1.0, defect);
        evaluate(dir, 0, "wall_force_rel_error");
        v = json_metric(dir, "free_surface_spread_rel", NULL) * 0.3 / 0.01;
        CHECK(v < spread_max[defect], "surface defect %d: spread %g dx (< %g)", defect, v, spread_max[defect]);
        v = (json_metric(dir, "depth", NULL) - 0.3) / 0.01;
        CHECK(fabs(v) < 0.05, "surface defect %d: depth - 0.3 m = %g dx (|.| < 0.05)", defect, v);
    }
}

/* 3D: a 0.1 x 0.05 m tank of four wall planes and a floor plane, h = 0.1 m, dx = 0.005. The
 * wall forces per unit width need the wetted widths 0.05 (x walls) and 0.1 (y walls). */
static int add_plane(const char *name, double cx, double cy, double cz, double nx, double ny, double nz,
                     double s0, double s1, double R)
{
    int j = add_body(name, LAHAR_MOTION_FIXED, 0);
    double c[3] = {cx, cy, cz}, n[3] = {nx, ny, nz}, size[2] = {s0, s1};
    lahar_shape_make_plane(&bodies[j].shape, c, n, size, R);
    return j;
}

static void hydro3d_run(const char *dir, double yfac)
{
    case_begin("hydrostatic", 3);
    const double Lx = 0.1, Ly = 0.05, h = 0.1, dx = 0.005, R = 0.002, rho = 1000.0, g = 9.81;
    cs.sph_dx = dx;
    int fl = add_plane("floor", 0.05, 0.025, -R, 0, 0, 1, 0.2, 0.2, R);
    int wx0 = add_plane("wall_xmin", -R, 0.025, 0.1, 1, 0, 0, 0.2, 0.3, R);
    int wx1 = add_plane("wall_xmax", Lx + R, 0.025, 0.1, -1, 0, 0, 0.2, 0.3, R);
    int wy0 = add_plane("wall_ymin", 0.05, -R, 0.1, 0, 1, 0, 0.2, 0.3, R);
    int wy1 = add_plane("wall_ymax", 0.05, Ly + R, 0.1, 0, -1, 0, 0.2, 0.3, R);
    metric("wall_force_rel_error", 0.01);
    metric("pressure_l2_rel_error", 0.01);
    run_out o;
    if (run_open(dir, &o))
        return;
    for (int k = 0; k <= 4; k++) {
        np = 0;
        for (int i = 0; i < 20; i++)
            for (int j = 0; j < 10; j++)
                for (int l = 0; l < 20; l++, np++) {
                    px[np] = (i + 0.5) * dx, py[np] = (j + 0.5) * dx, pz[np] = (l + 0.5) * dx;
                    pvx[np] = pvy[np] = 0.0, pden[np] = rho, ppr[np] = rho * g * (h - pz[np]);
                }
        memset(reports, 0, sizeof reports);
        double f = 0.5 * rho * g * h * h;
        reports[fl].force[2] = -rho * g * h * Lx * Ly;
        reports[wx0].force[0] = -f * Ly, reports[wx1].force[0] = f * Ly;
        reports[wy0].force[1] = -f * Lx * yfac, reports[wy1].force[1] = f * Lx;
        lahar_body_output_forces(o.bo, k, 0.1 * k, reports);
        run_snapshot(&o, k, 0.1 * k);
    }
    run_close(&o);
}

static void test_hydrostatic_3d(const char *base)
{
    char dir[1100];
    snprintf(dir, sizeof dir, "%s/hydro3d_pass", base);
    hydro3d_run(dir, 1.0);
    const double tol = 2.0 * LATTICE_LEVEL * 0.005 / 0.1; /* dx 0.005, h 0.1 */
    double v = evaluate(dir, 0, "wall_force_rel_error");
    CHECK(v < tol, "hydrostatic 3D exact: wall_force_rel_error %g (< %g)", v, tol);
    v = json_metric(dir, "depth", NULL);
    CHECK(fabs(v - 0.1) < LATTICE_LEVEL * 0.005, "hydrostatic 3D: depth %.9g (0.1)", v);
    v = json_metric(dir, "side_walls", NULL);
    CHECK(v == 4.0, "hydrostatic 3D: %g side walls (4)", v);
    snprintf(dir, sizeof dir, "%s/hydro3d_wall", base);
    hydro3d_run(dir, 0.97);
    v = evaluate(dir, 1, "wall_force_rel_error");
    CHECK(fabs(v - 0.03) < tol, "hydrostatic 3D y wall x 0.97: wall_force_rel_error %.10g (0.03)", v);
}

/* ---------------------------------------------------------------- floating box ---------- */

/* The box `lift` above its draft below the lattice's top row + dx/2 (0.3 m); the water's pressure is
 * hydrostatic about the level 0.3 m + p_shift (its zero). */
static void box_run(const char *dir, double lift, double p_shift)
{
    case_begin("floating_box", 2);
    const double W = 1.0, level = 0.3, dx = 0.01, R = 0.001, B = 0.2, hb = 0.1, rho_b = 500.0;
    cs.sph_dx = dx;
    add_segment("floor", -0.05, -R, W + 0.05, -R, R);
    add_segment("left", -R, 0.0, -R, 0.6, R);
    add_segment("right", W + R, 0.0, W + R, 0.6, R);
    int b = add_body("box", LAHAR_MOTION_FREE, 1);
    double half[2] = {0.5 * B - R, 0.5 * hb - R};
    lahar_shape_make_box2d(&bodies[b].shape, half, R);
    metric("draft_rel_error", 0.02);
    run_out o;
    if (run_open(dir, &o))
        return;
    double d_ref = rho_b * hb / 1000.0, xc = 0.5 * W;
    for (int k = 0; k <= 10; k++) {
        double t = 0.1 * k, yc = level - d_ref + 0.5 * hb + lift;
        /* released 1 cm low, settles by t = 0.5 */
        if (k < 5)
            yc -= 0.01 * (5 - k) / 5.0;
        memset(states, 0, sizeof states);
        states[b].x[0] = xc, states[b].x[1] = yc, states[b].q[0] = 1.0;
        np = 0;
        for (int i = 0; i < 100; i++)
            for (int j = 0; j < 30; j++) {
                double x = (i + 0.5) * dx, y = (j + 0.5) * dx;
                if (fabs(x - xc) < 0.5 * B && y > yc - 0.5 * hb)
                    continue;
                px[np] = x, py[np] = y, pvx[np] = pvy[np] = 0.0, pden[np] = 1000.0;
                ppr[np] = 1000.0 * 9.81 * (level + p_shift - y);
                np++;
            }
        memset(reports, 0, sizeof reports);
        lahar_body_output_forces(o.bo, k, t, reports);
        run_snapshot(&o, k, t);
    }
    run_close(&o);
}

static void test_floating_box(const char *base)
{
    char dir[1100];
    snprintf(dir, sizeof dir, "%s/box_pass", base);
    box_run(dir, 0.0, 0.0);
    double v = evaluate(dir, 0, "draft_rel_error");
    CHECK(v < 1e-9, "floating box exact: draft_rel_error %g", v);
    const double tol = LATTICE_LEVEL * 0.01 / 0.05; /* dx 0.01, draft 0.05 */
    v = json_metric(dir, "draft_level_rel_error", NULL);
    CHECK(v < tol, "floating box exact: draft_level_rel_error %g (< %g)", v, tol);
    snprintf(dir, sizeof dir, "%s/box_high", base);
    box_run(dir, 0.002, 0.0);
    v = evaluate(dir, 1, "draft_rel_error");
    CHECK(fabs(v - 0.04) < 1e-9, "floating box 2 mm high: draft_rel_error %.10g (0.04)", v);
    /* the draft is measured from the pressure's zero, not from the level gauges: the same box
     * in water whose pressure vanishes 2 mm above the tops floats 2 mm too deep (0.04) */
    snprintf(dir, sizeof dir, "%s/box_pressure", base);
    box_run(dir, 0.0, 0.002);
    v = evaluate(dir, 1, "draft_rel_error");
    CHECK(fabs(v - 0.04) < 1e-9, "floating box, pressure zero 2 mm up: draft_rel_error %.10g (0.04)", v);
    v = json_metric(dir, "draft_level_rel_error", NULL);
    CHECK(v < tol, "floating box, pressure zero 2 mm up: draft_level_rel_error %g (0)", v);
}

/* ---------------------------------------------------------------- sinking disc ---------- */

static void disc_run(const char *dir, int bad_particle)
{
    case_begin("sinking_disc", 2);
    const double W = 0.4, dx = 0.01, Rf = 0.002, Rd = 0.05, overlap = 1e-5;
    cs.sph_dx = dx;
    add_segment("floor", -0.05, -Rf, W + 0.05, -Rf, Rf);
    add_segment("left", -Rf, 0.0, -Rf, 0.6, Rf);
    add_segment("right", W + Rf, 0.0, W + Rf, 0.6, Rf);
    int b = add_body("disc", LAHAR_MOTION_FREE, 0);
    lahar_shape_make_sphere(&bodies[b].shape, Rd);
    metric("floor_penetration", 0.0);
    metric("final_speed_rel", 0.01);
    metric("rest_gap_rel", 0.01);
    run_out o;
    if (run_open(dir, &o))
        return;
    for (int k = 0; k <= 10; k++) {
        double t = 0.1 * k, s = k < 8 ? k / 8.0 : 1.0;
        double y0 = 0.4, y1 = Rd - overlap, yc = y0 + (y1 - y0) * s, xc = 0.2 + 0.01 * s;
        memset(states, 0, sizeof states);
        states[b].x[0] = xc, states[b].x[1] = yc, states[b].q[0] = 1.0;
        states[b].v[1] = k < 8 ? (y1 - y0) / 0.8 : 0.0, states[b].w[2] = k < 8 ? -0.2 : 0.0;
        np = 0;
        for (int i = 0; i < 40; i++)
            for (int j = 0; j < 50; j++) {
                double x = (i + 0.5) * dx, y = (j + 0.5) * dx;
                if (hypot(x - xc, y - yc) < Rd + 0.5 * dx)
                    continue;
                px[np] = x, py[np] = y, pvx[np] = pvy[np] = 0.0, pden[np] = 1000.0, ppr[np] = 0.0;
                np++;
            }
        if (bad_particle && k == 6)
            py[0] = -0.001; /* inside the floor's swept layer (core at -0.002, R = 0.002) */
        memset(reports, 0, sizeof reports);
        lahar_body_output_forces(o.bo, k, t, reports);
        run_snapshot(&o, k, t);
    }
    run_close(&o);
}

static void test_sinking_disc(const char *base)
{
    char dir[1100];
    snprintf(dir, sizeof dir, "%s/disc_pass", base);
    disc_run(dir, 0);
    double v = evaluate(dir, 0, "floor_penetration");
    CHECK(v == 0.0, "sinking disc: floor_penetration %g", v);
    v = json_metric(dir, "rest_gap_rel", NULL);
    CHECK(fabs(v - 1e-5 / 0.05) < 1e-9, "sinking disc: rest_gap_rel %g (2e-4)", v);
    v = json_metric(dir, "sink_distance", NULL);
    CHECK(fabs(v - (0.4 - 0.05 + 1e-5)) < 1e-12, "sinking disc: sink_distance %g", v);
    snprintf(dir, sizeof dir, "%s/disc_leak", base);
    disc_run(dir, 1);
    v = evaluate(dir, 1, "floor_penetration");
    CHECK(fabs(v - 0.001) < 1e-12, "sinking disc leak: floor_penetration %.10g (0.001)", v);
}

/* ---------------------------------------------------------------- dam break ------------- */

static void dam_run(const char *dir, int escape, int regress)
{
    case_begin("dam_break", 2);
    const double W = 1.0, a = 0.2, H0 = 0.4, dx = 0.01, R = 0.002;
    cs.sph_dx = dx;
    add_segment("floor", -0.05, -R, W + 0.05, -R, R);
    add_segment("left", -R, 0.0, -R, 0.8, R);
    add_segment("right", W + R, 0.0, W + R, 0.8, R);
    /* a fixed box high above the water: escape == 2 puts a particle at its centre, deep in its
     * core (0.05 from its edges, beyond the sweep radius) */
    int ob = add_body("obstacle", LAHAR_MOTION_FIXED, 0);
    double half[2] = {0.05, 0.05};
    lahar_shape_make_box2d(&bodies[ob].shape, half, R);
    /* as the case loader places fixed bodies: world-frame vertices, x = 0, identity q */
    const double I3[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, at[3] = {0.8, 0.7, 0.0};
    lahar_shape_transform(&bodies[ob].shape, I3, at, 1.0);
    /* a fixed wavy ledge above the water, 40 vertices (79 features: the check's feature-grid path);
     * escape == 4 puts a particle on its 21st vertex, inside its sweep */
    int ledge = add_body("ledge", LAHAR_MOTION_FIXED, 0);
    double lv[40][3];
    for (int i = 0; i < 40; i++)
        lv[i][0] = 0.1 + 0.6 * i / 39.0, lv[i][1] = 0.6 + 0.02 * sin(17.0 * lv[i][0]), lv[i][2] = 0.0;
    lahar_shape_make_polyline(&bodies[ledge].shape, lv, 40, 0, R, NULL, 0);
    bodies[ledge].convex = 0;
    metric("escaped_particles", 0.0);
    metric("mass_change", 0.0);
    metric("front_regression", 1.0);
    run_out o;
    if (run_open(dir, &o))
        return;
    for (int k = 0; k <= 10; k++) {
        double t = 0.1 * k;
        /* the column stretches along x (area kept) until its front reaches the far wall */
        double s = fmin(1.0 + 0.8 * k, (W - 0.5 * dx) / (a - 0.5 * dx));
        if (regress && k == 3)
            s = 2.1; /* behind snapshot 2 (s = 2.6): the front steps back 0.5 (a - dx/2) = 9.75 dx */
        np = 0;
        for (int i = 0; i < 20; i++)
            for (int j = 0; j < 40; j++, np++) {
                px[np] = (i + 0.5) * dx * s, py[np] = (j + 0.5) * dx / s, pvx[np] = pvy[np] = 0.0;
                pden[np] = 1000.0, ppr[np] = 0.0;
            }
        if (escape == 1 && k == 7)
            px[5] = W + 0.2;
        if (escape == 2 && k == 7)
            px[5] = 0.8, py[5] = 0.7;
        if (escape == 3 && k == 7)
            px[5] = 0.5, py[5] = 1.0; /* a splash above the walls (top 0.8): not escaped */
        if (escape == 4 && k == 7)
            px[5] = lv[20][0], py[5] = lv[20][1] + 0.5 * R;
        memset(reports, 0, sizeof reports);
        lahar_body_output_forces(o.bo, k, t, reports);
        run_snapshot(&o, k, t);
    }
    (void)H0;
    run_close(&o);
}

static void test_dam_break(const char *base)
{
    char dir[1100];
    snprintf(dir, sizeof dir, "%s/dam_pass", base);
    dam_run(dir, 0, 0);
    double v = evaluate(dir, 0, "escaped_particles");
    CHECK(v == 0.0, "dam break: escaped_particles %g", v);
    v = json_metric(dir, "front_regression", NULL);
    CHECK(v == 0.0, "dam break: front_regression %g", v);
    v = json_metric(dir, "column_height", NULL);
    CHECK(fabs(v - 0.4) < 1e-12, "dam break: column_height %g (0.4)", v);
    snprintf(dir, sizeof dir, "%s/dam_escape", base);
    dam_run(dir, 1, 0);
    v = evaluate(dir, 1, "escaped_particles");
    CHECK(v == 1.0, "dam break escape: escaped_particles %g (1)", v);
    snprintf(dir, sizeof dir, "%s/dam_inside", base);
    dam_run(dir, 2, 0);
    v = evaluate(dir, 1, "escaped_particles");
    CHECK(v == 1.0, "dam break particle inside the obstacle's core: escaped_particles %g (1)", v);
    snprintf(dir, sizeof dir, "%s/dam_splash", base);
    dam_run(dir, 3, 0);
    v = evaluate(dir, 0, "escaped_particles");
    CHECK(v == 0.0, "dam break splash above the walls: escaped_particles %g (0)", v);
    snprintf(dir, sizeof dir, "%s/dam_ledge", base);
    dam_run(dir, 4, 0);
    v = evaluate(dir, 1, "escaped_particles");
    CHECK(v == 1.0, "dam break particle in the sweep of a 79-feature ledge: escaped_particles %g (1)", v);
    snprintf(dir, sizeof dir, "%s/dam_regress", base);
    dam_run(dir, 0, 1);
    v = evaluate(dir, 1, "front_regression");
    CHECK(fabs(v - 9.75) < 1e-9, "dam break regress: front_regression %.10g (9.75 dx)", v);
}

/* A column a = 0.1 m wide, 0.2 m high (Martin & Moyce's n^2 = 2) whose front follows their
 * Figure 3 data times `zfac` (Z linear from 1 at T = 0 to the first data point, constant after
 * the last): the evaluator must find front_rel_error = |zfac - 1|. */
static const double mmT[] = {0.0, 0.832, 1.219, 1.997, 2.547, 3.345, 4.034, 4.418, 5.091,
                             5.685, 6.306, 6.822, 7.439, 8.031, 8.633, 9.237};
static const double mmZ[] = {1.0, 1.217, 1.474, 2.292, 2.995, 4.134, 4.944, 5.881, 6.980,
                             7.945, 8.966, 9.986, 10.963, 11.977, 13.005, 13.970};

static void mm_run(const char *dir, double zfac)
{
    case_begin("dam_break", 2);
    const double W = 1.6, a = 0.1, dx = 0.005, R = 0.002, g = 9.81;
    cs.sph_dx = dx, cs.output_interval = 0.02;
    add_segment("floor", -0.05, -R, W + 0.05, -R, R);
    add_segment("left", -R, 0.0, -R, 0.8, R);
    add_segment("right", W + R, 0.0, W + R, 0.8, R);
    metric("front_rel_error", 0.05);
    run_out o;
    if (run_open(dir, &o))
        return;
    const int n = (int)(sizeof mmT / sizeof mmT[0]);
    for (int k = 0; k <= 40; k++) {
        double t = 0.02 * k, T = t * sqrt(2.0 * g / a), Z = mmZ[n - 1];
        for (int i = 0; i + 1 < n; i++)
            if (T <= mmT[i + 1]) {
                Z = mmZ[i] + (mmZ[i + 1] - mmZ[i]) * (T - mmT[i]) / (mmT[i + 1] - mmT[i]);
                break;
            }
        Z = k == 0 ? 1.0 : zfac * Z;
        /* furthest particle at 19.5 dx s, the water's edge dx/2 beyond: z = Z a */
        double s = (Z * a - 0.5 * dx) / (19.5 * dx);
        np = 0;
        for (int i = 0; i < 20; i++)
            for (int j = 0; j < 40; j++, np++) {
                px[np] = (i + 0.5) * dx * s, py[np] = (j + 0.5) * dx / s, pvx[np] = pvy[np] = 0.0;
                pden[np] = 1000.0, ppr[np] = 0.0;
            }
        memset(reports, 0, sizeof reports);
        lahar_body_output_forces(o.bo, k, t, reports);
        run_snapshot(&o, k, t);
    }
    run_close(&o);
}

static void test_martin_moyce(const char *base)
{
    char dir[1100];
    snprintf(dir, sizeof dir, "%s/dam_mm_pass", base);
    mm_run(dir, 1.0);
    double v = evaluate(dir, 0, "front_rel_error");
    CHECK(v < 1e-9, "dam break on Martin & Moyce's data: front_rel_error %g", v);
    snprintf(dir, sizeof dir, "%s/dam_mm_fast", base);
    mm_run(dir, 1.1);
    v = evaluate(dir, 1, "front_rel_error");
    CHECK(fabs(v - 0.1) < 1e-9, "dam break front 10 %% ahead: front_rel_error %.10g (0.1)", v);
}

/* ---------------------------------------------------------------- errors ---------------- */

static void test_errors(const char *base)
{
    char dir[1100], other[1100];
    /* body output only: the fluid references need particles.h5 */
    snprintf(dir, sizeof dir, "%s/no_particles", base);
    mkdir(dir, 0755);
    case_begin("poiseuille", 2);
    add_segment("floor", 0, 0, 1, 0, 0.01);
    char err[512];
    lahar_body_output *bo = lahar_body_output_open(dir, &cs, err, sizeof err);
    CHECK(bo, "open: %s", err);
    if (bo) {
        memset(states, 0, sizeof states);
        states[0].q[0] = 1.0;
        lahar_body_output_snapshot(bo, 0, 0.0, states);
        lahar_body_output_close(bo);
    }
    evaluate(dir, 2, "x");
    /* particles without velocities */
    snprintf(dir, sizeof dir, "%s/no_velocity", base);
    poiseuille_run(dir, 1.0, 1.0); /* writes all fields; rewrite the particles without velocity */
    cs.output_fields = LAHAR_PFIELD_PRESSURE;
    lahar_particle_output *po = lahar_particle_output_open(dir, &cs, cs.output_fields, err, sizeof err);
    if (po) {
        lahar_particles_view v = {np, px, py, NULL, NULL, NULL, NULL, NULL, ppr, NULL, NULL, {NULL}, NULL, NULL};
        lahar_particle_output_snapshot(po, 0, 1.0, &v);
        lahar_particle_output_close(po);
    }
    evaluate(dir, 2, "x");
    /* a 3D case on 2D output */
    snprintf(other, sizeof other, "%s/poiseuille_pass", base);
    cs.dim = 3;
    evaluate(other, 2, "x");
}

int main(int argc, char **argv)
{
    const char *base = argc > 1 ? argv[1] : "test_check_fluid_dir";
    mkdir(base, 0755);
    test_poiseuille(base);
    test_cylinder(base);
    test_hydrostatic(base);
    test_hydrostatic_3d(base);
    test_floating_box(base);
    test_sinking_disc(base);
    test_dam_break(base);
    test_martin_moyce(base);
    test_errors(base);
    case_begin("none", 2);
    if (failures) {
        fprintf(stderr, "test_check_fluid: %d failure(s)\n", failures);
        return 1;
    }
    printf("test_check_fluid: all checks passed\n");
    return 0;
}
