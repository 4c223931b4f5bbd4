/* Resting contacts and edge-edge contacts of boxes:
 * - a box on a plane and a stack of three boxes settle without drift (horizontal drift < 1e-6 m,
 *   kinetic energy -> 0, heights at the stacked rest heights within the static overlaps);
 * - two boxes with crossed edges: one edge-edge contact with normal +z and overlap
 *   (Ra + Rb) - d, force kn delta (static check), and a box dropped edge-on onto the other's edge
 *   rebounds straight up with the restitution e (dynamic check). */
#include <math.h>
#include <stdio.h>
#include "dem_test_util.h"
#include "geometry.h"
#include "vec.h"

static void resting_stack(int nbox)
{
    const double g = 9.81, kn = 1e6, r = 0.01, rp = 0.01;
    const double gv[3] = {0, 0, -g};
    const double halves[3] = {0.2, 0.15, 0.1};
    lahar_case c;
    dem_test_case_init(&c, 3, gv, 4);
    int m = dem_test_material(&c, "rock", LAHAR_CONTACT_LINEAR, 2500.0, kn, 0, 0, 0.3, 0.5);
    const double centre[3] = {0, 0, 0}, n[3] = {0, 0, 1}, size[2] = {4, 4};
    dem_test_plane(&c, "floor", m, centre, n, size, rp);
    double z = rp, zrest[3];
    for (int k = 0; k < nbox; k++) {
        double h = halves[k];
        const double half[3] = {h, h, h}, q[4] = {1, 0, 0, 0};
        double x[3] = {0.01 * k, -0.005 * k, z + r + h + 1e-4}; /* 0.1 mm gaps: they settle */
        char name[16];
        snprintf(name, sizeof name, "box%d", k);
        dem_test_box(&c, name, m, half, r, x, q, LAHAR_MOTION_FREE);
        zrest[k] = z + r + h;
        z += 2.0 * (h + r);
    }
    const lahar_dem_engine_ops *ops;
    lahar_dem_engine *e = dem_test_engine(&c, &ops);
    char err[512];
    double drift = 0.0, ke = 0.0, xrest[4][2] = {{0}};
    for (int k = 0; k < 4000; k++) {
        if (ops->advance(e, 1e-3, NULL, err, sizeof err) < 0) {
            dem_test_check(0, "advance: %s", err);
            break;
        }
        if (k >= 2000) /* after settling: watch for creep */
            for (int b = 1; b <= nbox; b++) {
                lahar_body_state st;
                ops->get_state(e, b, &st);
                if (k == 2000) {
                    xrest[b][0] = st.x[0];
                    xrest[b][1] = st.x[1];
                }
                drift = fmax(drift, hypot(st.x[0] - xrest[b][0], st.x[1] - xrest[b][1]));
            }
        ke = ops->kinetic_energy(e);
    }
    double wtot = 0.0;
    for (int b = 1; b <= nbox; b++) wtot += c.bodies[b].mass * g;
    dem_test_check(drift < 1e-6, "stack of %d: horizontal drift %.2e m over 2 s of rest (< 1e-6)", nbox, drift);
    dem_test_check(ke < 1e-9 * wtot, "stack of %d: kinetic energy %.2e J after 4 s (-> 0)", nbox, ke);
    /* each interface carries the weight above it on 4 corner springs: overlap W_above / (4 kn) */
    double wabove = wtot, sink = 0.0;
    for (int b = 1; b <= nbox; b++) {
        sink += wabove / (4.0 * kn);
        zrest[b - 1] -= sink;
        wabove -= c.bodies[b].mass * g;
    }
    for (int b = 1; b <= nbox; b++) {
        lahar_body_state st;
        ops->get_state(e, b, &st);
        char what[64];
        snprintf(what, sizeof what, "stack of %d: box %d height", nbox, b - 1);
        dem_test_abs(what, st.x[2], zrest[b - 1], 1e-5); /* off-centre loads tilt by microns */
    }
    lahar_body_report rep;
    ops->get_report(e, 0, &rep);
    dem_test_rel("floor carries the whole weight", -rep.force[2], wtot, 1e-4);
    ops->destroy(e);
    dem_test_case_free(&c);
}

static void crossed_edges(void)
{
    const double kn = 1e6, r = 0.03, e_rest = 0.6;
    const double g0[3] = {0, 0, 0};
    lahar_case c;
    dem_test_case_init(&c, 3, g0, 2);
    c.dem_dt_safety = 0.001;
    int m = dem_test_material(&c, "rock", LAHAR_CONTACT_LINEAR, 2500.0, kn, 0, 0, e_rest, 0.5);
    const double half[3] = {0.5, 0.5, 0.5};
    double h = 0.5 * sqrt(2.0), qa[4], qb[4];
    q_store(q_axis_angle(v3(1, 0, 0), M_PI / 4), qa); /* top edge along x */
    q_store(q_axis_angle(v3(0, 1, 0), M_PI / 4), qb); /* bottom edge along y */
    const double xa[3] = {0, 0, 0};
    double core = 0.055; /* core distance; swept surfaces overlap by 2 r - core = 5 mm */
    double xb[3] = {0.1, -0.05, 2 * h + core};
    dem_test_box(&c, "lower", m, half, r, xa, qa, LAHAR_MOTION_FIXED);
    int b = dem_test_box(&c, "upper", m, half, r, xb, qb, LAHAR_MOTION_FREE);
    double d = geom_body_core_distance(&c.bodies[0].shape, xa, qa, &c.bodies[1].shape, xb, qb);
    dem_test_abs("crossed edges: core distance", d, core, 1e-12);
    const lahar_dem_engine_ops *ops;
    lahar_dem_engine *e = dem_test_engine(&c, &ops);
    lahar_body_report rep;
    ops->get_report(e, b, &rep);
    dem_test_check(ops->ncontacts(e) == 1, "crossed edges: %d contact (1, edge-edge)", ops->ncontacts(e));
    double fmag = sqrt(rep.force[0] * rep.force[0] + rep.force[1] * rep.force[1] + rep.force[2] * rep.force[2]);
    dem_test_rel("crossed edges: force kn (Ra + Rb - d)", fmag, kn * (2 * r - core), 1e-9);
    dem_test_abs("crossed edges: normal z component", rep.force[2] / fmag, 1.0, 1e-12);
    ops->destroy(e);
    /* dynamic: centred above the edge, falling at v0 */
    const double v0 = 0.1; /* max overlap v0 sqrt(m/kn) = 5.5 mm < r/2 */
    c.bodies[b].x[0] = c.bodies[b].x[1] = 0.0;
    c.bodies[b].x[2] = 2 * h + 2 * r + 1e-6;
    c.bodies[b].v[2] = -v0;
    e = dem_test_engine(&c, &ops);
    char err[512];
    lahar_body_state st;
    int touched = 0;
    for (int k = 0; k < 100000; k++) {
        if (ops->advance(e, ops->stable_dt(e), NULL, err, sizeof err) < 0) {
            dem_test_check(0, "advance: %s", err);
            break;
        }
        if (ops->ncontacts(e) > 0) touched = 1;
        if (touched && ops->ncontacts(e) == 0) break;
    }
    ops->get_state(e, b, &st);
    dem_test_rel("edge-on impact: rebound / impact speed", st.v[2] / v0, e_rest, 0.01);
    dem_test_check(fabs(st.v[0]) + fabs(st.v[1]) < 1e-9 * v0, "edge-on impact: rebound straight up (|vx|+|vy| = %.2e)",
                   fabs(st.v[0]) + fabs(st.v[1]));
    ops->destroy(e);
    dem_test_case_free(&c);
}

int main(void)
{
    resting_stack(1);
    resting_stack(3);
    crossed_edges();
    return dem_test_failures ? 1 : 0;
}
