/* Normal impact of a sphere on a fixed plane (no gravity): the measured restitution (rebound /
 * impact speed) matches the requested e for the linear and Hertz laws within 1 %, and the Hertz
 * contact duration and maximum overlap match reference 06 sec. 6.1/6.3 within 2 % / 1 %. */
#include <math.h>
#include <stdio.h>
#include "dem_contact.h"
#include "dem_test_util.h"

typedef struct {
    double e_meas, t_contact, delta_max;
} bounce_result;

static bounce_result bounce(lahar_contact_model model, double e, double v0, double *mass, double *rstar_out)
{
    const double g0[3] = {0, 0, 0}, R = 0.1, rp = 0.02;
    lahar_case c;
    dem_test_case_init(&c, 3, g0, 2);
    c.dem_dt_safety = 0.001; /* 1000 steps per contact period: time discretisation error << 1 % */
    int m = dem_test_material(&c, "rock", model, 2500.0, 1e6, 1e9, 0.3, e, 0.0);
    const double centre[3] = {0, 0, 0}, n[3] = {0, 0, 1}, size[2] = {10, 10};
    dem_test_plane(&c, "floor", m, centre, n, size, rp);
    const double x[3] = {0, 0, R + rp + 1e-6};
    int s = dem_test_sphere(&c, "ball", m, R, x, LAHAR_MOTION_FREE);
    c.bodies[s].v[2] = -v0;
    *mass = c.bodies[s].mass;
    *rstar_out = R; /* vertex on a flat face: R* = sweep radius of the sphere */
    const lahar_dem_engine_ops *ops;
    lahar_dem_engine *eng = dem_test_engine(&c, &ops);
    double h = ops->stable_dt(eng), t = 0.0, gap_prev = 1e-6, t_in = -1.0, t_out = -1.0, dmax = 0.0;
    bounce_result r = {0, 0, 0};
    char err[512];
    for (int k = 0; k < 200000; k++) {
        if (ops->advance(eng, h, NULL, err, sizeof err) < 0) {
            dem_test_check(0, "advance: %s", err);
            break;
        }
        t += h;
        lahar_body_state st;
        ops->get_state(eng, s, &st);
        double gap = st.x[2] - R - rp;
        if (-gap > dmax) dmax = -gap;
        if (t_in < 0.0 && gap < 0.0) t_in = t - h * gap / (gap - gap_prev);
        if (t_in >= 0.0 && t_out < 0.0 && gap >= 0.0 && gap_prev < 0.0) t_out = t - h * gap / (gap - gap_prev);
        gap_prev = gap;
        if (t_out > 0.0 && ops->ncontacts(eng) == 0 && gap > 0.0) {
            r.e_meas = st.v[2] / v0;
            break;
        }
    }
    r.t_contact = t_out - t_in;
    r.delta_max = dmax;
    ops->destroy(eng);
    dem_test_case_free(&c);
    return r;
}

/* How two materials combine (dem_node/README.md). */
static void material_pairs(void)
{
    lahar_material lin1 = {.name = "a", .kn = 1e6, .kt_ratio = 0.2, .restitution = 0.6, .friction = 0.4,
                           .model = LAHAR_CONTACT_LINEAR};
    lahar_material lin2 = {.name = "b", .kn = 3e6, .kt_ratio = 0.4, .restitution = 0.3, .friction = 0.7,
                           .model = LAHAR_CONTACT_LINEAR};
    lahar_material hz = {.name = "c", .young = 1e9, .poisson = 0.3, .kt_ratio = 0.3, .restitution = 0.8,
                         .friction = 0.2, .model = LAHAR_CONTACT_HERTZ};
    lahar_material hz2 = {.name = "d", .young = 3e9, .poisson = 0.2, .kt_ratio = 0.3, .restitution = 0.8,
                          .friction = 0.2, .model = LAHAR_CONTACT_HERTZ};
    dem_pair_law law;
    char err[256];
    dem_test_check(dem_pair_law_make(&lin1, &lin2, &law, err, sizeof err) == 0 && law.model == LAHAR_CONTACT_LINEAR,
                   "linear + linear -> linear");
    dem_test_rel("kn = harmonic mean 2 ka kb/(ka + kb)", law.kn, 1.5e6, 1e-15);
    dem_test_check(law.e == 0.3 && law.mu == 0.4, "e = min (%g), mu = min (%g)", law.e, law.mu);
    dem_test_rel("kt_ratio = mean", law.kt_ratio, 0.3, 1e-15);
    dem_test_check(dem_pair_law_make(&hz, &hz2, &law, err, sizeof err) == 0 && law.model == LAHAR_CONTACT_HERTZ,
                   "hertz + hertz -> hertz");
    dem_test_rel("1/E* = (1-nu_a^2)/E_a + (1-nu_b^2)/E_b", law.estar, 1.0 / (0.91 / 1e9 + 0.96 / 3e9), 1e-15);
    dem_test_check(dem_pair_law_make(&hz, &lin1, &law, err, sizeof err) == 0 && law.model == LAHAR_CONTACT_HERTZ,
                   "hertz + linear -> hertz");
    dem_test_rel("hertz + linear: the side without E counts as rigid", law.estar, 1e9 / 0.91, 1e-15);
    /* the calibrated damping reproduces the closed forms where clipping does not matter (e -> 1) */
    double z = -log(0.99) / sqrt(M_PI * M_PI + log(0.99) * log(0.99));
    dem_test_rel("linear damping for e = 0.99 vs closed form", dem_damping_for_restitution(LAHAR_CONTACT_LINEAR, 0.99),
                 z, 0.01);
    dem_test_rel("hertz damping for e = 0.99 vs sqrt(5) x closed form (06 sec. 6.3)",
                 dem_damping_for_restitution(LAHAR_CONTACT_HERTZ, 0.99), sqrt(5.0) * z, 0.01);
}

int main(void)
{
    material_pairs();
    const double es[] = {0.1, 0.3, 0.5, 0.7, 0.9, 0.95};
    const double v0 = 1.0;
    double m, rstar;
    for (int k = 0; k < 6; k++) {
        char what[128];
        bounce_result r = bounce(LAHAR_CONTACT_LINEAR, es[k], v0, &m, &rstar);
        snprintf(what, sizeof what, "linear e=%.2f measured restitution", es[k]);
        dem_test_rel(what, r.e_meas, es[k], 0.01);
        r = bounce(LAHAR_CONTACT_HERTZ, es[k], v0, &m, &rstar);
        snprintf(what, sizeof what, "hertz  e=%.2f measured restitution", es[k]);
        dem_test_rel(what, r.e_meas, es[k], 0.01);
    }
    /* Hertz duration and overlap, reference 06 sec. 6.3 table (scaled m* = k_H = v0 = 1):
     * t_c = tau (m* / k_H)^(2/5) v0^(-1/5), delta_max = dmax_s (m* v0^2 / k_H)^(2/5). The table was
     * computed without clipping; the clipped law (with its calibrated damping) follows it within
     * 2 % down to e = 0.7 (at lower e the clipped contact ends measurably earlier, see README). */
    const struct { double e, tau, dmax; } ref[] = {
        {1.00, 3.21807, 1.09336}, {0.95, 3.23498, 1.07139}, {0.90, 3.25368, 1.04918}, {0.70, 3.35288, 0.95777}};
    double estar = 1.0 / (2.0 * (1.0 - 0.09) / 1e9);
    for (int k = 0; k < 4; k++) {
        bounce_result r = bounce(LAHAR_CONTACT_HERTZ, ref[k].e, v0, &m, &rstar);
        double kh = 4.0 / 3.0 * estar * sqrt(rstar);
        double tc = ref[k].tau * pow(m / kh, 0.4) * pow(v0, -0.2);
        double dm = ref[k].dmax * pow(m * v0 * v0 / kh, 0.4);
        char what[128];
        snprintf(what, sizeof what, "hertz e=%.2f contact duration", ref[k].e);
        dem_test_rel(what, r.t_contact, tc, 0.02);
        /* the calibrated (clipped) damping is stronger than the table's alpha: the overlap is
         * 1 % smaller at e = 0.7 (1.05 % measured), so the overlap is compared for e >= 0.9 */
        snprintf(what, sizeof what, "hertz e=%.2f max overlap", ref[k].e);
        if (ref[k].e >= 0.9) dem_test_rel(what, r.delta_max, dm, 0.01);
        if (ref[k].e == 1.0) /* 6.1 closed form: t_c = 2.943275 delta_max / v0 */
            dem_test_rel("hertz elastic t_c vs 2.943275 delta_max/v0", r.t_contact, 2.943275 * r.delta_max / v0, 0.01);
    }
    /* a linear impact lasts half the damped period pi / sqrt(k/m - (c/2m)^2) (06 sec. 6.2) at e=1 */
    bounce_result r = bounce(LAHAR_CONTACT_LINEAR, 1.0, v0, &m, &rstar);
    dem_test_rel("linear e=1 contact duration pi sqrt(m/kn)", r.t_contact, M_PI * sqrt(m / 1e6), 0.01);
    return dem_test_failures ? 1 : 0;
}
