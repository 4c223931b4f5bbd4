/* Contact laws of the sphero-polyhedra DEM engine: how two materials combine into a pair law,
 * the normal (linear or Hertz) and tangential (spring with Coulomb limit) forces, and the damping
 * calibrated from the coefficient of restitution. Formulas and conventions: dem_node/README.md. */
#ifndef LAHAR_DEM_CONTACT_H
#define LAHAR_DEM_CONTACT_H
#include <math.h>
#include <stddef.h>
#include "scene.h"
#include "vec.h"

typedef struct {
    lahar_contact_model model;
    double kn;       /* linear: normal stiffness (harmonic mean of the two materials) */
    double estar;    /* Hertz: effective modulus E*, 1/E* = (1-nu_a^2)/E_a + (1-nu_b^2)/E_b */
    double kt_ratio; /* tangential / normal (secant) stiffness */
    double e;        /* restitution, min of the two */
    double mu;       /* Coulomb friction, min of the two */
    double sqrt_kt_ratio; /* sqrt(kt_ratio): tangential damping / normal damping */
    double damp;     /* linear: damping ratio zeta; Hertz: alpha (Tsuji form), both calibrated for
                        the clipped force so that a binary impact rebounds with exactly e */
} dem_pair_law;

/* Combine two materials. Returns 0, or -1 with a message (e.g. Hertz without Young's modulus). */
int dem_pair_law_make(const lahar_material *a, const lahar_material *b, dem_pair_law *out,
                      char *err, size_t errlen);

/* Restitution of a binary impact under `model` with damping parameter `damp` (zeta or alpha) and
 * the normal force clipped at zero, from the scaled equation of motion (m* = k = v0 = 1). */
double dem_restitution_clipped(lahar_contact_model model, double damp);

/* Damping parameter (zeta for linear, alpha for Hertz) whose clipped impact rebounds with e. */
double dem_damping_for_restitution(lahar_contact_model model, double e);

/* The two force laws are inline: they are the inner loop of both narrow phases (general and the
 * sphere fast path). */

/* The per-pair constants of the normal law (they depend on m* and R* only, so a neighbour list can
 * keep them): Hertz k0 = k_H = 4/3 E* sqrt(R*), c0 = alpha sqrt(m* k_H); linear k0 = kn,
 * c0 = 2 zeta sqrt(kn m*). */
typedef struct {
    double k0, c0;
} dem_pair_consts;

static inline dem_pair_consts dem_pair_consts_make(const dem_pair_law *law, double mstar, double rstar)
{
    dem_pair_consts pc;
    if (law->model == LAHAR_CONTACT_HERTZ) {
        pc.k0 = 4.0 / 3.0 * law->estar * sqrt(rstar);
        pc.c0 = law->damp * sqrt(mstar * pc.k0);
    } else {
        pc.k0 = law->kn;
        pc.c0 = 2.0 * law->damp * sqrt(law->kn * mstar);
    }
    return pc;
}

/* Normal force magnitude (>= 0, clipped) for overlap delta > 0 and overlap rate delta_dot
 * (> 0 approaching), the dashpot multiplied by damp_scale (1 for a single contact point); also the
 * current normal stiffness (secant for Hertz) and damping coefficient used for the tangential ones. */
static inline double dem_normal_force_pc(const dem_pair_law *law, const dem_pair_consts *pc, double delta,
                                         double delta_dot, double damp_scale, double *k_secant, double *c_normal)
{
    double k, c;
    if (law->model == LAHAR_CONTACT_HERTZ) {
        /* Canelas et al. 2015 eq. 14-15 with exponent 3/2 (the printed 3/4 is a typo, shared/papers/README):
         * F = k_H delta^(3/2) + alpha sqrt(m* k_H) delta^(1/4) delta_dot, k_H = 4/3 E* sqrt(R*) */
        double sd = sqrt(delta);
        k = pc->k0 * sd;
        c = damp_scale * pc->c0 * sqrt(sd);
    } else {
        /* linear spring-dashpot, c = 2 zeta sqrt(kn m*) (reference 06 sec. 6.2) */
        k = pc->k0;
        c = damp_scale * pc->c0;
    }
    double f = k * delta + c * delta_dot;
    *k_secant = k;
    *c_normal = c;
    return f > 0.0 ? f : 0.0;
}

static inline double dem_normal_force(const dem_pair_law *law, double delta, double delta_dot, double mstar,
                                      double rstar, double damp_scale, double *k_secant, double *c_normal)
{
    dem_pair_consts pc = dem_pair_consts_make(law, mstar, rstar);
    return dem_normal_force_pc(law, &pc, delta, delta_dot, damp_scale, k_secant, c_normal);
}

/* Elastic contact period of the pair: linear 2 pi sqrt(m* / kn), twice the contact duration; Hertz: the elastic
 * Hertz duration 2.868266 (m*^2/(R* E*^2 v))^(1/5) (reference 06 sec. 6.1) at impact speed v. */
double dem_contact_period(const dem_pair_law *law, double mstar, double rstar, double v_impact);

/* The engines' stable step (dem_node/engines/spheropoly/README.md "Step size"): safety x the shortest contact period
 * of every free body against every material it may meet, m* = m/2 against free bodies (when there
 * are two or more), m against the others, R* the larger of the body's sweep radius and the largest
 * one of that material, Hertz at the impact speed v_impact = v_max + sqrt(2 |g| L) + 1 m/s
 * (dem_impact_speed: L the scene diagonal, v_max the fastest initial body). When no free body can
 * meet anything: dt_max (safety x 1 s when dt_max is 0). laws: nmat x nmat. */
typedef struct {
    int material, free;
    double radius, mass; /* sweep radius, mass */
} dem_step_body;
double dem_impact_speed(double vmax, double gravity, double extent);
/* Substeps of a coupling step dt: n = ceil(dt / dt_stable), at least 1 (each of length dt / n). */
long dem_substeps(double dt, double dt_stable);
double dem_stable_dt(const dem_step_body *bodies, int nbody, const dem_pair_law *laws, int nmat, double vimpact,
                     double safety, double dt_max);

/* Tangential force (world vector) from the spring xi (already rotated onto the tangent plane and
 * advanced by the tangential displacement of this step), the tangential relative velocity vt, the
 * normal force fn and the normal stiffness/damping. When the trial force exceeds mu fn the spring is
 * truncated so that it alone carries the Coulomb force (sliding). */
static inline vec3 dem_tangential_force(const dem_pair_law *law, vec3 *xi, vec3 vt, double fn, double k_secant,
                                        double c_normal)
{
    /* k_t = kt_ratio k_n (secant k_n for Hertz), c_t = sqrt(kt_ratio) c_n: the same damping ratio
     * as the normal direction (Canelas et al. 2015 uses 2/7 for both, which changes the ratio). */
    double kt = law->kt_ratio * k_secant;
    double ct = law->sqrt_kt_ratio * c_normal;
    vec3 f = v3_add(v3_scale(*xi, -kt), v3_scale(vt, -ct));
    double fmax = law->mu * fn;
    double fm2 = v3_norm2(f);
    if (fm2 > fmax * fmax) { /* squares: the root only when sliding */
        double fm = sqrt(fm2);
        f = fm > 0.0 ? v3_scale(f, fmax / fm) : v3(0.0, 0.0, 0.0);
        *xi = kt > 0.0 ? v3_scale(f, -1.0 / kt) : v3(0.0, 0.0, 0.0);
    }
    return f;
}

#endif
