/* `lahar check` evaluation on synthetic runs written through the real output writers:
 *  - restitution: a sphere falling from 1 m with instantaneous bounces of restitution e_true on
 *    a floor (exact piecewise parabolas, snapshots every 10 ms). The floor (e = 0.7) is the only
 *    fixed body with contacts in forces.h5; an untouched wall has e = 0.3, the ball e = 0.9, so
 *    the reference is e = 0.7. e_true = 0.7 must pass (error ~ rounding), e_true = 0.75 must fail
 *    with restitution_rel_error = 0.05/0.7.
 *  - incline_roll: a disc (I = m R^2/2) on a 20 degree segment incline with mu = 0.5 (rolls):
 *    a = 2/3 g sin(theta) must pass (also after a hop off the slope at the start), a = g sin(theta)
 *    (frictionless) must fail with error 0.5.
 *  - errors: missing output, unknown reference, unknown metric -> 2.
 *   test_check OUTDIR */
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

static lahar_material mats[3];
static lahar_body bodies[3];

static void material(int i, const char *name, double e, double mu)
{
    memset(&mats[i], 0, sizeof mats[i]);
    snprintf(mats[i].name, sizeof mats[i].name, "%s", name);
    mats[i].density = 2000, mats[i].restitution = e, mats[i].friction = mu, mats[i].kn = 1e6;
}

static void body(int i, const char *name, int mat, lahar_motion motion)
{
    snprintf(bodies[i].name, sizeof bodies[i].name, "%s", name);
    bodies[i].material = mat;
    bodies[i].motion = motion;
    bodies[i].q[0] = 1.0;
    bodies[i].convex = 1;
}

static void free_bodies(int n)
{
    for (int i = 0; i < n; i++)
        lahar_shape_free(&bodies[i].shape);
    memset(bodies, 0, sizeof bodies);
}

/* Read check.json: pass flag and the value of `metric`. */
static int read_json(const char *dir, const char *metric, int *pass, double *value)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/check.json", dir);
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    char buf[1 << 17];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = 0;
    cJSON *root = cJSON_Parse(buf);
    if (!root)
        return -1;
    cJSON *p = cJSON_GetObjectItem(root, "pass");
    *pass = cJSON_IsTrue(p);
    cJSON *m = cJSON_GetObjectItem(cJSON_GetObjectItem(root, "metrics"), metric);
    cJSON *v = m ? cJSON_GetObjectItem(m, "value") : NULL;
    *value = v ? v->valuedouble : NAN;
    cJSON_Delete(root);
    return 0;
}

/* Ball height under gravity with instantaneous bounces at h_c (exact, piecewise parabolas). */
static void bounce_state(double t, double h0, double hc, double g, double e, double *h, double *u, int *bounce_row)
{
    double tb = sqrt(2.0 * (h0 - hc) / g); /* first impact */
    if (t < tb) {
        *h = h0 - 0.5 * g * t * t, *u = -g * t;
        return;
    }
    double t0 = tb, u0 = e * g * tb;
    (void)bounce_row;
    while (t > t0 + 2.0 * u0 / g && u0 > 1e-9) {
        t0 += 2.0 * u0 / g;
        u0 *= e;
    }
    *h = hc + u0 * (t - t0) - 0.5 * g * (t - t0) * (t - t0), *u = u0 - g * (t - t0);
}

static void run_restitution(const char *dir, double e_true, lahar_case *c)
{
    mkdir(dir, 0755);
    material(0, "ball_mat", 0.9, 0.5);
    material(1, "floor_mat", 0.7, 0.5);
    material(2, "wall_mat", 0.3, 0.5);
    body(0, "ball", 0, LAHAR_MOTION_FREE);
    body(1, "floor", 1, LAHAR_MOTION_FIXED);
    body(2, "wall", 2, LAHAR_MOTION_FIXED);
    double cen[3] = {0, 0, 0}, nz[3] = {0, 0, 1}, size[2] = {2, 2}, cw[3] = {1.5, 0, 0.5}, nx[3] = {-1, 0, 0};
    lahar_shape_make_sphere(&bodies[0].shape, 0.05);
    lahar_shape_make_plane(&bodies[1].shape, cen, nz, size, 0.001);
    lahar_shape_make_plane(&bodies[2].shape, cw, nx, size, 0.001);
    bodies[0].mass = 1.0;
    memset(c, 0, sizeof *c);
    snprintf(c->path, sizeof c->path, "synthetic_bounce.yaml");
    c->dim = 3, c->gravity[2] = -9.81, c->t_end = 2.0, c->output_interval = 0.01, c->output_forces = 1;
    c->nmaterial = 3, c->materials = mats, c->nbody = 3, c->bodies = bodies;
    c->check.enabled = 1;
    snprintf(c->check.reference, sizeof c->check.reference, "restitution");
    c->check.nmetric = 1;
    snprintf(c->check.metric[0].name, sizeof c->check.metric[0].name, "restitution_rel_error");
    c->check.metric[0].bound = 0.01;
    char err[512];
    lahar_body_output *o = lahar_body_output_open(dir, c, err, sizeof err);
    CHECK(o, "open: %s", err);
    if (!o)
        return;
    double g = 9.81, h0 = 1.0, hc = 0.051, prev_u = 0.0;
    for (int k = 0; k <= 200; k++) {
        double t = 0.01 * k, h, u;
        bounce_state(t, h0, hc, g, e_true, &h, &u, NULL);
        lahar_body_state s[3];
        memset(s, 0, sizeof s);
        for (int b = 0; b < 3; b++)
            s[b].q[0] = 1.0;
        s[0].x[2] = h, s[0].v[2] = u;
        lahar_body_report r[3];
        memset(r, 0, sizeof r);
        r[1].ncontacts = (k > 0 && prev_u < 0.0 && u > 0.0); /* the floor touched since last row */
        prev_u = u;
        lahar_body_output_snapshot(o, k, t, s);
        lahar_body_output_forces(o, k, t, r);
    }
    lahar_body_output_close(o);
}

static void run_incline(const char *dir, double accel, int hop, lahar_case *c)
{
    mkdir(dir, 0755);
    const double th = 20.0 * M_PI / 180.0, R = 0.1, r_inc = 0.001;
    material(0, "disc_mat", 0.5, 0.5);
    material(1, "slope_mat", 0.5, 0.6);
    body(0, "disc", 0, LAHAR_MOTION_FREE);
    body(1, "slope", 1, LAHAR_MOTION_FIXED);
    vec3 d = v3(cos(th), -sin(th), 0), n = v3(sin(th), cos(th), 0);
    double p0[3] = {0, 0, 0}, p1[3];
    v3_store(v3_scale(d, 3.0), p1);
    lahar_shape_make_sphere(&bodies[0].shape, R);
    lahar_shape_make_segment(&bodies[1].shape, p0, p1, r_inc);
    bodies[0].mass = 2.0, bodies[0].inertia[2] = 0.5 * 2.0 * R * R;
    memset(c, 0, sizeof *c);
    snprintf(c->path, sizeof c->path, "synthetic_incline.yaml");
    c->dim = 2, c->gravity[1] = -9.81, c->t_end = 1.0, c->output_interval = 0.02, c->output_forces = 1;
    c->nmaterial = 2, c->materials = mats, c->nbody = 2, c->bodies = bodies;
    c->check.enabled = 1;
    snprintf(c->check.reference, sizeof c->check.reference, "incline_roll");
    c->check.nmetric = 1;
    snprintf(c->check.metric[0].name, sizeof c->check.metric[0].name, "accel_rel_error");
    c->check.metric[0].bound = 0.01;
    char err[512];
    lahar_body_output *o = lahar_body_output_open(dir, c, err, sizeof err);
    CHECK(o, "open: %s", err);
    if (!o)
        return;
    vec3 x0 = v3_add(v3_scale(d, 0.2), v3_scale(n, R + r_inc));
    for (int k = 0; k <= 50; k++) {
        double t = 0.02 * k;
        lahar_body_state s[2];
        memset(s, 0, sizeof s);
        s[0].q[0] = s[1].q[0] = 1.0;
        v3_store(v3_axpy(0.5 * accel * t * t, d, x0), s[0].x);
        if (hop && k >= 1 && k <= 4) /* touches at t = 0, in the air for 4 snapshots, then rolls */
            v3_store(v3_axpy(0.05, n, v3_load(s[0].x)), s[0].x);
        v3_store(v3_scale(d, accel * t), s[0].v);
        s[0].w[2] = -accel * t / R;
        lahar_body_output_snapshot(o, k, t, s);
    }
    lahar_body_output_close(o);
}

int main(int argc, char **argv)
{
    const char *base = argc > 1 ? argv[1] : "test_check_dir";
    mkdir(base, 0755);
    char dir[1100];
    lahar_case c;
    int pass;
    double v;

    /* restitution: pass (with the plot), then fail */
    snprintf(dir, sizeof dir, "%s/bounce_pass", base);
    run_restitution(dir, 0.7, &c);
    int rc = lahar_check_evaluate(&c, dir);
    CHECK(rc == 0, "restitution e_true = e_ref: status %d", rc);
    CHECK(read_json(dir, "restitution_rel_error", &pass, &v) == 0 && pass && v < 1e-9,
          "check.json: pass %d, restitution_rel_error %g", pass, v);
    char png[1200];
    snprintf(png, sizeof png, "%s/check.png", dir);
    CHECK(access(png, R_OK) == 0, "no %s (python3 + matplotlib needed)", png);
    /* without python3/matplotlib: said on stderr, check.json still written, status unchanged */
    setenv("LAHAR_PYTHON", "/nonexistent/python3", 1);
    char json[1200];
    snprintf(json, sizeof json, "%s/check.json", dir);
    unlink(json);
    CHECK(lahar_check_evaluate(&c, dir) == 0 && access(json, R_OK) == 0, "no python: status or check.json wrong");
    /* a metric the reference does not have */
    snprintf(c.check.metric[0].name, sizeof c.check.metric[0].name, "restitution_error");
    setenv("LAHAR_CHECK_NO_PLOT", "1", 1);
    CHECK(lahar_check_evaluate(&c, dir) == 2, "unknown metric must give status 2");
    /* an unknown reference */
    snprintf(c.check.reference, sizeof c.check.reference, "poiseuille_typo");
    CHECK(lahar_check_evaluate(&c, dir) == 2, "unknown reference must give status 2");
    free_bodies(3);

    snprintf(dir, sizeof dir, "%s/bounce_fail", base);
    run_restitution(dir, 0.75, &c);
    rc = lahar_check_evaluate(&c, dir);
    CHECK(rc == 1, "restitution e_true = 0.75 vs 0.7: status %d", rc);
    CHECK(read_json(dir, "restitution_rel_error", &pass, &v) == 0 && !pass && fabs(v - 0.05 / 0.7) < 1e-9,
          "check.json: pass %d, restitution_rel_error %.12g (expected %.12g)", pass, v, 0.05 / 0.7);
    free_bodies(3);

    /* incline: rolling acceleration passes, frictionless fails */
    const double g = 9.81, th = 20.0 * M_PI / 180.0;
    snprintf(dir, sizeof dir, "%s/incline_pass", base);
    run_incline(dir, 2.0 / 3.0 * g * sin(th), 0, &c);
    rc = lahar_check_evaluate(&c, dir);
    CHECK(rc == 0, "incline 2/3 g sin(theta): status %d", rc);
    char other[1200];
    snprintf(other, sizeof other, "%s/bounce_fail", base);
    CHECK(lahar_check_evaluate(&c, other) == 2, "output of another case (3 bodies, case has 2) must give status 2");
    CHECK(read_json(dir, "accel_rel_error", &pass, &v) == 0 && pass && v < 1e-9, "incline pass: %d %g", pass, v);
    free_bodies(2);

    /* a hop at the start: the fit uses the longest contact run, not the first touch */
    snprintf(dir, sizeof dir, "%s/incline_hop", base);
    run_incline(dir, 2.0 / 3.0 * g * sin(th), 1, &c);
    rc = lahar_check_evaluate(&c, dir);
    CHECK(rc == 0, "incline with a hop at the start: status %d", rc);
    free_bodies(2);

    snprintf(dir, sizeof dir, "%s/incline_fail", base);
    run_incline(dir, g * sin(th), 0, &c);
    rc = lahar_check_evaluate(&c, dir);
    CHECK(rc == 1, "incline g sin(theta): status %d", rc);
    CHECK(read_json(dir, "accel_rel_error", &pass, &v) == 0 && !pass && fabs(v - 0.5) < 1e-9,
          "incline fail: pass %d, accel_rel_error %.12g (expected 0.5)", pass, v);
    free_bodies(2);

    /* no output at all */
    snprintf(dir, sizeof dir, "%s/empty", base);
    mkdir(dir, 0755);
    c.check.enabled = 1;
    snprintf(c.check.reference, sizeof c.check.reference, "restitution");
    c.nbody = 0;
    CHECK(lahar_check_evaluate(&c, dir) == 2, "missing bodies.h5 must give status 2");
    CHECK(read_json(dir, "x", &pass, &v) == 0 && !pass, "error check.json says pass false");

    if (failures) {
        fprintf(stderr, "test_check: %d failure(s)\n", failures);
        return 1;
    }
    printf("test_check: all checks passed\n");
    return 0;
}
