/* A prescribed gate (infinite mass, constant velocity) hits a ball resting on a frictionless floor:
 * the ball leaves at (1 + e) v_gate (impact with an infinitely heavy wall moving at v_gate), the gate
 * keeps x0 + v t and reports the contact force it feels; a prescribed spinning paddle keeps its
 * angular velocity and turns by w t; a box dropped flat rebounds with e. */
#include <math.h>
#include <stdio.h>
#include "dem_test_util.h"
#include "vec.h"

/* A box dropped flat (4 corners at once) on the floor rebounds with e: the per-point dashpots are
 * shared among the parallel points (dem_node/README.md, multi-point contacts). */
static void flat_drop(double e_rest)
{
    const double g0[3] = {0, 0, 0}, v0 = 0.2, kn = 1e6;
    lahar_case c;
    dem_test_case_init(&c, 3, g0, 2);
    c.dem_dt_safety = 0.001;
    int m = dem_test_material(&c, "steel", LAHAR_CONTACT_LINEAR, 2500.0, kn, 0, 0, e_rest, 0.3);
    const double centre[3] = {0, 0, 0}, n[3] = {0, 0, 1}, size[2] = {6, 6};
    dem_test_plane(&c, "floor", m, centre, n, size, 0.01);
    const double half[3] = {0.1, 0.15, 0.05}, q1[4] = {1, 0, 0, 0}, x[3] = {0, 0, 0.05 + 0.02 + 1e-6};
    int b = dem_test_box(&c, "box", m, half, 0.01, x, q1, LAHAR_MOTION_FREE);
    c.bodies[b].v[2] = -v0;
    const lahar_dem_engine_ops *ops;
    lahar_dem_engine *e = dem_test_engine(&c, &ops);
    char err[512];
    int touched = 0, maxc = 0;
    for (int k = 0; k < 100000; k++) {
        if (ops->advance(e, ops->stable_dt(e), NULL, err, sizeof err) < 0) {
            dem_test_check(0, "advance: %s", err);
            break;
        }
        int nc = ops->ncontacts(e);
        maxc = nc > maxc ? nc : maxc;
        if (nc > 0) touched = 1;
        if (touched && nc == 0) break;
    }
    lahar_body_state st;
    ops->get_state(e, b, &st);
    char what[96];
    snprintf(what, sizeof what, "box dropped flat on %d corners, e=%.1f: rebound / impact speed", maxc, e_rest);
    dem_test_rel(what, st.v[2] / v0, e_rest, 0.01);
    ops->destroy(e);
    dem_test_case_free(&c);
}

int main(void)
{
    flat_drop(0.5);
    flat_drop(0.2);
    const double g = 9.81, e_rest = 0.5, vg = 0.3, kn = 1e6;
    const double gv[3] = {0, 0, -g};
    lahar_case c;
    dem_test_case_init(&c, 3, gv, 4);
    c.dem_dt_safety = 0.001;
    int m = dem_test_material(&c, "steel", LAHAR_CONTACT_LINEAR, 2500.0, kn, 0, 0, e_rest, 0.0);
    const double centre[3] = {0, 0, 0}, n[3] = {0, 0, 1}, size[2] = {6, 6};
    dem_test_plane(&c, "floor", m, centre, n, size, 0.01);
    const double half[3] = {0.1, 0.1, 0.1}, q1[4] = {1, 0, 0, 0};
    double xb[3] = {0.0, 0, 0};
    /* a ball, not a box: with a face-to-face impact the 4 corner dashpots act in parallel and
     * double the damping ratio of the body (see dem_node/README.md, known limits) */
    int box = dem_test_sphere(&c, "ball", m, 0.11, xb, LAHAR_MOTION_FREE);
    c.bodies[box].x[2] = 0.11 + 0.01 - c.bodies[box].mass * g / kn;
    (void)half;
    const double gh[3] = {0.05, 0.3, 0.3};
    double xg[3] = {-0.11 - 0.05 - 0.01 - 0.01, 0, 0.32}; /* the ball centre faces the gate face */ /* 1 cm gap to the box */
    int gate = dem_test_box(&c, "gate", m, gh, 0.01, xg, q1, LAHAR_MOTION_PRESCRIBED);
    c.bodies[gate].v[0] = vg;
    double xp[3] = {2.0, 2.0, 1.0};
    int paddle = dem_test_box(&c, "paddle", m, gh, 0.01, xp, q1, LAHAR_MOTION_PRESCRIBED);
    c.bodies[paddle].w[2] = 2.0;
    const lahar_dem_engine_ops *ops;
    lahar_dem_engine *e = dem_test_engine(&c, &ops);
    char err[512];
    double t = 0.0, fmax_gate = 0.0;
    const double dt = 1e-3;
    for (int k = 0; k < 300; k++) {
        if (ops->advance(e, dt, NULL, err, sizeof err) < 0) {
            dem_test_check(0, "advance: %s", err);
            break;
        }
        t += dt;
        lahar_body_report rep;
        ops->get_report(e, gate, &rep);
        fmax_gate = fmax(fmax_gate, -rep.force[0]);
    }
    lahar_body_state sb, sg, sp;
    ops->get_state(e, box, &sb);
    ops->get_state(e, gate, &sg);
    ops->get_state(e, paddle, &sp);
    dem_test_rel("ball speed after the gate's push vs (1 + e) v_gate", sb.v[0], (1.0 + e_rest) * vg, 0.01);
    dem_test_abs("gate position vs x0 + v t", sg.x[0], xg[0] + vg * t, 1e-12);
    dem_test_check(sg.v[0] == vg && sg.x[2] == xg[2], "gate keeps its velocity and height");
    dem_test_check(fmax_gate > 0.0, "gate reported the ball pushing back: max %.3g N", fmax_gate);
    /* paddle: q = rotation by w t about z */
    double ang = 2.0 * atan2(sp.q[3], sp.q[0]);
    dem_test_abs("paddle turned by w t", ang, 2.0 * t, 1e-9);
    dem_test_check(sp.w[2] == 2.0, "paddle keeps w = 2 rad/s");
    ops->destroy(e);
    dem_test_case_free(&c);
    return dem_test_failures ? 1 : 0;
}
