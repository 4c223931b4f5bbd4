/* A box launched sliding on a horizontal plane stops after v0^2 / (2 mu g) (reference 06 sec. 6.6)
 * within 1 %, and then stays at rest. */
#include <math.h>
#include <stdio.h>
#include "dem_test_util.h"

/* 2D: a rectangle sliding on a segment wall rests on its 2 lower corners (vertex-edge contacts) */
static void slide_2d(void)
{
    const double g = 9.81, mu = 0.4, v0 = 1.5, kn = 1e6, rp = 0.01, r = 0.01;
    const double gv[3] = {0, -g, 0};
    lahar_case c;
    dem_test_case_init(&c, 2, gv, 2);
    int m = dem_test_material(&c, "rock", LAHAR_CONTACT_LINEAR, 2500.0, kn, 0, 0, 0.3, mu);
    const double a[3] = {-3, 0, 0}, b3[3] = {3, 0, 0};
    dem_test_segment(&c, "ground", m, a, b3, rp);
    const double half[3] = {0.15, 0.1, 0}, x[3] = {-1, 0, 0}, q[4] = {1, 0, 0, 0};
    int b = dem_test_box(&c, "block2d", m, half, r, x, q, LAHAR_MOTION_FREE);
    c.bodies[b].x[1] = half[1] + r + rp - c.bodies[b].mass * g / (2.0 * kn);
    c.bodies[b].v[0] = v0;
    const lahar_dem_engine_ops *ops;
    lahar_dem_engine *e = dem_test_engine(&c, &ops);
    char err[512];
    for (int k = 0; k < 1000; k++)
        if (ops->advance(e, 1e-3, NULL, err, sizeof err) < 0) {
            dem_test_check(0, "advance: %s", err);
            break;
        }
    lahar_body_state st;
    ops->get_state(e, b, &st);
    dem_test_rel("2D box stop distance vs v0^2/(2 mu g)", st.x[0] - x[0], v0 * v0 / (2.0 * mu * g), 0.01);
    lahar_body_report rep;
    ops->get_report(e, b, &rep);
    dem_test_check(rep.ncontacts == 2, "2D box rests on 2 corner contacts: %d", rep.ncontacts);
    dem_test_rel("2D box at rest: contact force balances the weight", rep.force[1], c.bodies[b].mass * g, 1e-3);
    ops->destroy(e);
    dem_test_case_free(&c);
}

int main(void)
{
    slide_2d();
    const double g = 9.81, mu = 0.3, v0 = 2.0, kn = 1e6, rp = 0.01, r = 0.01;
    const double gv[3] = {0, 0, -g};
    lahar_case c;
    dem_test_case_init(&c, 3, gv, 2);
    int m = dem_test_material(&c, "rock", LAHAR_CONTACT_LINEAR, 2500.0, kn, 0, 0, 0.3, mu);
    const double centre[3] = {0, 0, 0}, n[3] = {0, 0, 1}, size[2] = {10, 10};
    dem_test_plane(&c, "floor", m, centre, n, size, rp);
    const double half[3] = {0.1, 0.1, 0.1}, x[3] = {-2, 0, 0}, q[4] = {1, 0, 0, 0};
    int b = dem_test_box(&c, "block", m, half, r, x, q, LAHAR_MOTION_FREE);
    c.bodies[b].x[2] = half[2] + r + rp - c.bodies[b].mass * g / (4.0 * kn); /* 4 corner contacts at rest */
    c.bodies[b].v[0] = v0;
    const lahar_dem_engine_ops *ops;
    lahar_dem_engine *e = dem_test_engine(&c, &ops);
    char err[512];
    lahar_body_state st;
    double ke_end = 0.0;
    for (int k = 0; k < 1500; k++) {
        if (ops->advance(e, 1e-3, NULL, err, sizeof err) < 0) {
            dem_test_check(0, "advance: %s", err);
            break;
        }
        if (k == 1499) ke_end = ops->kinetic_energy(e);
    }
    ops->get_state(e, b, &st);
    dem_test_rel("box stop distance vs v0^2/(2 mu g)", st.x[0] - x[0], v0 * v0 / (2.0 * mu * g), 0.01);
    dem_test_check(ke_end < 1e-6 * 0.5 * c.bodies[b].mass * v0 * v0, "box at rest after 1.5 s: KE %.3g J", ke_end);
    lahar_body_report rep;
    ops->get_report(e, b, &rep);
    dem_test_check(rep.ncontacts == 4, "box rests on 4 vertex-face contacts: %d", rep.ncontacts);
    dem_test_rel("box at rest: contact force balances the weight", rep.force[2], c.bodies[b].mass * g, 1e-3);
    ops->destroy(e);
    dem_test_case_free(&c);
    return dem_test_failures ? 1 : 0;
}
