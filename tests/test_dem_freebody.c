/* Torque-free asymmetric box: kinetic energy and angular momentum conserved to 1e-6 (relative)
 * over 1e5 steps; spin about the intermediate principal axis flips (tennis-racket / Dzhanibekov
 * effect: the body-frame angular velocity along that axis changes sign), spin about the axes of
 * minimum and maximum inertia stays stable. */
#include <math.h>
#include <stdio.h>
#include "dem_test_util.h"
#include "vec.h"

/* returns min and max (over the run) of the body-frame omega component along `axis` */
static void spin(int axis, double *wmin, double *wmax, double *ke_err, double *l_err, const char *label)
{
    const double g0[3] = {0, 0, 0};
    lahar_case c;
    dem_test_case_init(&c, 3, g0, 1);
    c.dt_max = 1e-4; /* nothing to touch: the engine step is dt_max */
    int m = dem_test_material(&c, "steel", LAHAR_CONTACT_LINEAR, 1000.0, 1e6, 0, 0, 0.5, 0.3);
    const double half[3] = {0.3, 0.2, 0.1}, x[3] = {0, 0, 0}, q[4] = {1, 0, 0, 0};
    int b = dem_test_box(&c, "racket", m, half, 0.01, x, q, LAHAR_MOTION_FREE);
    /* I_x < I_y < I_z: x is the minimum, y the intermediate, z the maximum axis */
    double w[3] = {1e-2, 1e-2, 1e-2};
    w[axis] = 10.0;
    for (int k = 0; k < 3; k++) c.bodies[b].w[k] = w[k];
    const double *I = c.bodies[b].inertia;
    const lahar_dem_engine_ops *ops;
    lahar_dem_engine *e = dem_test_engine(&c, &ops);
    dem_test_check(I[0] < I[1] && I[1] < I[2], "%s: principal moments %.4g < %.4g < %.4g", label, I[0], I[1], I[2]);
    double ke0 = ops->kinetic_energy(e);
    vec3 L0 = v3(I[0] * w[0], I[1] * w[1], I[2] * w[2]);
    *wmin = *wmax = w[axis];
    *ke_err = *l_err = 0.0;
    char err[256];
    for (int k = 0; k < 100000; k++) {
        if (ops->advance(e, 1e-4, NULL, err, sizeof err) != 1) {
            dem_test_check(0, "advance: %s", err);
            break;
        }
        lahar_body_state st;
        ops->get_state(e, b, &st);
        quat qq = q_load(st.q);
        vec3 wb = q_rotate_inv(qq, v3_load(st.w));
        vec3 L = q_rotate(qq, v3(I[0] * wb.x, I[1] * wb.y, I[2] * wb.z));
        double wa = v3_get(wb, axis);
        if (wa < *wmin) *wmin = wa;
        if (wa > *wmax) *wmax = wa;
        double ke = 0.5 * (I[0] * wb.x * wb.x + I[1] * wb.y * wb.y + I[2] * wb.z * wb.z);
        *ke_err = fmax(*ke_err, fabs(ke - ke0) / ke0);
        *l_err = fmax(*l_err, v3_norm(v3_sub(L, L0)) / v3_norm(L0));
        if (k == 99999) dem_test_rel("engine kinetic_energy vs 1/2 w.I.w", ops->kinetic_energy(e), ke, 1e-12);
    }
    ops->destroy(e);
    dem_test_case_free(&c);
}

int main(void)
{
    const char *names[3] = {"minimum axis", "intermediate axis", "maximum axis"};
    for (int axis = 0; axis < 3; axis++) {
        double wmin, wmax, ke, l;
        spin(axis, &wmin, &wmax, &ke, &l, names[axis]);
        char what[128];
        dem_test_check(ke <= 1e-6, "%s: max relative kinetic energy error %.2e over 1e5 steps (<= 1e-6)", names[axis], ke);
        dem_test_check(l <= 1e-6, "%s: max relative angular momentum error %.2e over 1e5 steps (<= 1e-6)", names[axis], l);
        snprintf(what, sizeof what, "%s: body-frame spin range [%.4g, %.4g] (initial 10)", names[axis], wmin, wmax);
        if (axis == 1) dem_test_check(wmin < -9.0, "%s flips to about -10", what);
        else dem_test_check(wmin > 9.9 && wmax < 10.1, "%s stays within 1 %%", what);
    }
    return dem_test_failures ? 1 : 0;
}
