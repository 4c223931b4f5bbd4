/* The checks of the state after each step: particles that crossed a body surface (named, with the
 * body, as an instability report) and the particle checks of common/protocol/instability.h (finite
 * state, density within stability.density_band). */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "sph_soil_model.h"
#include "sph_node_run.h"

void sph_node_crossing_message(const sph_node *s, int64_t k, double t, char *err, size_t n)
{
    const sph_coupling *cp = &s->f.cpl;
    int b = cp->cross_body;
    if (k < 0) {
        snprintf(err, n, "particle %lld starts inside body %d '%s' (%.3g m inside the surface; %lld particle%s "
                 "inside bodies at t = 0): move the particle block or the body",
                 (long long)cp->cross_particle_id, b, b >= 0 && b < s->nbody ? s->ns.scene.bodies[b].name : "?",
                 cp->cross_depth, (long long)cp->crossings, cp->crossings == 1 ? "" : "s");
        return;
    }
    snprintf(err, n,
             "particle %lld crossed the surface of body %d '%s' in step %lld (t = %.9g s; %.3g m inside; %lld "
             "particle%s inside bodies); the last snapshot is the state after that step",
             (long long)cp->cross_particle_id, b, b >= 0 && b < s->nbody ? s->ns.scene.bodies[b].name : "?",
             (long long)k, t, cp->cross_depth, (long long)cp->crossings, cp->crossings == 1 ? "" : "s");
}

/* Position of the particle with this id (a search: only after a failure), 0 if found. */
static int sph_node_find_particle(const sph_particles *p, int64_t id, double x[3])
{
    for (int64_t i = 0; i < p->n; i++)
        if (p->id[i] == id) {
            x[0] = p->x[i], x[1] = p->y[i], x[2] = p->z[i];
            return 0;
        }
    x[0] = x[1] = x[2] = NAN;
    return -1;
}

/* The crossing of step k (sph_node_crossing_message) as an instability report. */
void sph_node_crossing_report(const sph_node *s, int64_t k, double t, lahar_instability *u)
{
    const sph_coupling *cp = &s->f.cpl;
    int b = cp->cross_body;
    memset(u, 0, sizeof *u);
    snprintf(u->what, sizeof u->what, "crossing");
    snprintf(u->kind, sizeof u->kind, "particle");
    u->id = cp->cross_particle_id;
    snprintf(u->name, sizeof u->name, "%s", b >= 0 && b < s->nbody ? s->ns.scene.bodies[b].name : "?");
    sph_node_find_particle(&s->f.p, u->id, u->x);
    u->step = k;
    u->t = t;
    u->value = cp->cross_depth;
    u->limit = 0.0;
    sph_node_crossing_message(s, k, t, u->text, sizeof u->text);
}

/* The particle checks of common/protocol/instability.h on the state after step k (time t): every
 * position, velocity and density finite, and rho / rho0 within stability.density_band. One
 * streaming pass counts the failures (a sum: the same for any thread count); only when there are
 * some, a serial pass names the worst: the non-finite particle of lowest id, else the one
 * farthest outside the band (largest |ln(rho / rho0)|, lowest id on a tie). Returns the count. */
int64_t sph_node_check_particles(const sph_node *s, int64_t k, double t, lahar_instability *u)
{
    const sph_particles *p = &s->f.p;
    const int64_t n = p->n;
    const double rho_water = s->ns.scene.sph_density;
    const double *band = s->ns.scene.stability.density_band;
    /* rho0 of particle I and the band's lower end: the water's; soil particles (sph_soil.h) have
     * their material's rest density and no lower end: their density comes from continuity and
     * thins where the soil spreads or separates (physical for a granular material, and there is no
     * EOS to turn it into a pressure), but a soil particle squeezed to band[1] x its rest density is
     * an impact the step did not resolve (a 2D block into a wall at 20 m/s reached 5.6 x) */
    const double rho_soil = s->f.has_soil ? s->f.soil.mat.density : NAN;
#define SPH_NODE_SOIL(I) (s->f.has_soil && p->phase[I] == SPH_SOIL_PHASE)
#define SPH_NODE_RHO0(I) (SPH_NODE_SOIL(I) ? rho_soil : rho_water)
#define SPH_NODE_IN_BAND(I) \
    ((SPH_NODE_SOIL(I) || p->rho[I] >= band[0] * SPH_NODE_RHO0(I)) && p->rho[I] <= band[1] * SPH_NODE_RHO0(I))
    int64_t bad = 0;
#pragma omp parallel for schedule(static) reduction(+ : bad) if (n >= SPH_OMP_MIN_LIGHT)
    for (int64_t i = 0; i < n; i++) {
        /* a NaN or an infinity in any component makes the sum non-finite; a NaN density fails
         * the band test too */
        double sum = p->x[i] + p->y[i] + p->z[i] + p->vx[i] + p->vy[i] + p->vz[i];
        bad += !(isfinite(sum) && isfinite(p->rho[i]) && SPH_NODE_IN_BAND(i));
    }
    if (bad == 0)
        return 0;
    int64_t worst = -1, worst_nf = -1;
    double dev_max = -1.0;
    for (int64_t i = 0; i < n; i++) {
        double sum = p->x[i] + p->y[i] + p->z[i] + p->vx[i] + p->vy[i] + p->vz[i];
        if (!isfinite(sum) || !isfinite(p->rho[i])) {
            if (worst_nf < 0 || p->id[i] < p->id[worst_nf])
                worst_nf = i;
        } else if (!SPH_NODE_IN_BAND(i)) {
            double dev = fabs(log(p->rho[i] / SPH_NODE_RHO0(i)));
            if (dev > dev_max || (dev == dev_max && p->id[i] < p->id[worst])) {
                dev_max = dev;
                worst = i;
            }
        }
    }
    int64_t i = worst_nf >= 0 ? worst_nf : worst;
    memset(u, 0, sizeof *u);
    snprintf(u->kind, sizeof u->kind, "particle");
    u->id = p->id[i];
    u->x[0] = p->x[i], u->x[1] = p->y[i], u->x[2] = p->z[i];
    u->step = k;
    u->t = t;
    const double r = p->rho[i] / SPH_NODE_RHO0(i);
    const int soil = SPH_NODE_SOIL(i);
#undef SPH_NODE_IN_BAND
#undef SPH_NODE_RHO0
#undef SPH_NODE_SOIL
    if (worst_nf >= 0) {
        snprintf(u->what, sizeof u->what, "non-finite state");
        u->value = NAN;
        u->limit = NAN;
        snprintf(u->text, sizeof u->text,
                 "particle %lld has a non-finite state after step %lld (t = %.9g s): x = (%.4g, %.4g, %.4g) m, "
                 "v = (%.3g, %.3g, %.3g) m/s, rho/rho0 = %.4g; %lld particle%s failed the checks; the last snapshot is "
                 "that state",
                 (long long)u->id, (long long)k, t, p->x[i], p->y[i], p->z[i], p->vx[i], p->vy[i], p->vz[i], r,
                 (long long)bad, bad == 1 ? "" : "s");
    } else {
        snprintf(u->what, sizeof u->what, "density out of band");
        u->value = r;
        u->limit = r < band[0] ? band[0] : band[1];
        snprintf(u->text, sizeof u->text,
                 "%s particle %lld at (%.4g, %.4g, %.4g) m has rho/rho0 = %.4g outside stability.density_band [%g, %g]%s "
                 "after step %lld (t = %.9g s); %lld particle%s outside; the last snapshot is that state",
                 soil ? "soil" : "water", (long long)u->id, u->x[0], u->x[1], u->x[2], r, band[0], band[1],
                 soil ? " (soil: its upper end only)" : "", (long long)k, t, (long long)bad, bad == 1 ? "" : "s");
    }
    return bad;
}
