/* SPH-DEM coupling (sph_coupling.h; Trujillo-Vela et al. 2020 section 4). */
#include "sph_coupling.h"
#include "soa_alloc.h"
#include "sph_riemann.h"
#include "sph_wall_ghost.h"
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "geometry.h"
#include "vec.h"

void sph_coupling_set_periodic(sph_coupling *c, const int periodic[3], const double lo[3], const double hi[3])
{
    for (int a = 0; a < 3; a++) {
        c->periodic[a] = periodic && periodic[a] && !(a == 2 && c->dim == 2) && hi[a] > lo[a];
        c->period[a] = c->periodic[a] ? hi[a] - lo[a] : 0.0;
        c->period_lo[a] = c->periodic[a] ? lo[a] : 0.0;
    }
}

int sph_coupling_init(sph_coupling *c, int dim, int nbody, const lahar_body *bodies, const kernel *k, double dx,
                      double m_sph, double mu, lahar_sph_wall_viscous viscous, int64_t particle_cap)
{
    memset(c, 0, sizeof *c);
    c->dim = dim;
    c->nbody = nbody;
    c->bodies = bodies;
    c->k = *k;
    c->eps = 0.5 * dx;
    c->mu = mu;
    c->viscous = viscous;
    c->m_min = m_sph;
    for (int b = 0; b < nbody; b++)
        if (bodies[b].motion == LAHAR_MOTION_FREE && bodies[b].mass > 0.0 && bodies[b].mass < c->m_min)
            c->m_min = bodies[b].mass;
    c->pcap = particle_cap < 1 ? 1 : particle_cap;
    int nb = nbody > 0 ? nbody : 1;
    c->bound = calloc((size_t)nb, sizeof *c->bound);
    c->box = calloc((size_t)nb, sizeof *c->box);
    c->force = calloc((size_t)nb, sizeof *c->force);
    c->torque = calloc((size_t)nb, sizeof *c->torque);
    c->body_start = calloc((size_t)nb + 1, sizeof *c->body_start);
    c->body_fill = calloc((size_t)nb, sizeof *c->body_fill);
    c->slot_n = lahar_soa_calloc((size_t)c->pcap, sizeof *c->slot_n);
    c->near = lahar_soa_calloc((size_t)c->pcap, sizeof *c->near);
    c->slot_body = lahar_soa_calloc((size_t)c->pcap * SPH_COUPLING_MAX_PER_PARTICLE, sizeof *c->slot_body);
    c->slot = lahar_soa_calloc((size_t)c->pcap * SPH_COUPLING_MAX_PER_PARTICLE, sizeof *c->slot);
    c->contacts_cap = 1024;
    c->contacts = calloc((size_t)c->contacts_cap, sizeof *c->contacts);
    if (!c->bound || !c->box || !c->force || !c->torque || !c->body_start || !c->body_fill || !c->slot_n || !c->slot_body ||
        !c->slot || !c->contacts) {
        sph_coupling_free(c);
        return -1;
    }
    for (int b = 0; b < nbody; b++) {
        const lahar_shape *s = &bodies[b].shape;
        double r = 0.0;
        for (int i = 0; i < s->nv; i++)
            r = fmax(r, v3_norm(v3_load(s->v[i])));
        c->bound[b] = r + s->radius;
        /* fixed bodies never move: a tight world box culls most particles (long walls) */
        for (int a = 0; a < 3; a++) {
            c->box[b][a] = s->nv ? INFINITY : -INFINITY;
            c->box[b][3 + a] = s->nv ? -INFINITY : INFINITY;
        }
        for (int i = 0; i < s->nv; i++) {
            vec3 w = geom_world_vertex(s, bodies[b].x, bodies[b].q, i);
            for (int a = 0; a < 3; a++) {
                c->box[b][a] = fmin(c->box[b][a], v3_get(w, a) - s->radius);
                c->box[b][3 + a] = fmax(c->box[b][3 + a], v3_get(w, a) + s->radius);
            }
        }
    }
    if (geom_body_grids_build(&c->grids, bodies, nbody) != 0) {
        sph_coupling_free(c);
        return -1;
    }
    /* the half-space factor, tabulated from eps/2 (closest a particle is let near) to the support */
    c->gtab_d0 = 0.5 * c->eps;
    c->gtab_dd = (k->support - c->gtab_d0) / SPH_COUPLING_GTAB;
    for (int i = 0; i <= SPH_COUPLING_GTAB; i++)
        c->gtab[i] = sph_ghost_layers(k, dim, c->gtab_d0 + i * c->gtab_dd, dx);
    /* discs and spheres (one core point): their own table, layers curved with the surface */
    for (int b = 0; b < nbody; b++) {
        const lahar_shape *s = &bodies[b].shape;
        if (s->nv != 1 || s->ne != 0 || s->nf != 0 || !(s->radius > 0.0))
            continue;
        if (!c->gtab_body) {
            c->gtab_body = calloc((size_t)nb, sizeof *c->gtab_body);
            if (!c->gtab_body) {
                sph_coupling_free(c);
                return -1;
            }
        }
        c->gtab_body[b] = malloc((SPH_COUPLING_GTAB + 1) * sizeof **c->gtab_body);
        if (!c->gtab_body[b]) {
            sph_coupling_free(c);
            return -1;
        }
        for (int i = 0; i <= SPH_COUPLING_GTAB; i++)
            c->gtab_body[b][i] = sph_ghost_layers_curved(k, dim, c->gtab_d0 + i * c->gtab_dd, dx, s->radius);
    }
    return 0;
}

void sph_coupling_free(sph_coupling *c)
{
    geom_body_grids_free(&c->grids);
    free(c->box);
    for (int b = 0; c->gtab_body && b < c->nbody; b++)
        free(c->gtab_body[b]);
    free(c->gtab_body);
    free(c->bound);
    free(c->force);
    free(c->torque);
    free(c->body_start);
    free(c->body_fill);
    lahar_soa_free(c->slot_n);
    lahar_soa_free(c->near);
    lahar_soa_free(c->slot_body);
    lahar_soa_free(c->slot);
    free(c->contacts);
    lahar_soa_free(c->soil_hist_body);
    lahar_soa_free(c->soil_hist_d);
    free(c->wtab);
    free(c->qtab);
    lahar_soa_free(c->soil_lw);
    lahar_soa_free(c->soil_lw_on);
    memset(c, 0, sizeof *c);
}

int sph_coupling_enable_soil(sph_coupling *c, double mu_phi)
{
    const size_t n = (size_t)c->pcap * SPH_COUPLING_MAX_PER_PARTICLE;
    lahar_soa_free(c->soil_hist_body);
    lahar_soa_free(c->soil_hist_d);
    c->soil_hist_body = lahar_soa_calloc(n, sizeof *c->soil_hist_body);
    c->soil_hist_d = lahar_soa_calloc(n, sizeof *c->soil_hist_d);
    if (!c->soil_hist_body || !c->soil_hist_d) {
        lahar_soa_free(c->soil_hist_body), lahar_soa_free(c->soil_hist_d);
        c->soil_hist_body = NULL, c->soil_hist_d = NULL;
        return -1;
    }
    for (size_t k = 0; k < n; k++)
        c->soil_hist_body[k] = -1;
    c->mu_phi = mu_phi;
    return 0;
}

/* The tangential spring of soil particle `id` on body b (sph_coupling.h, eq. 22-25): from its
 * last value (0 for a new pair) to this step's, capped; returns the tangential force on the
 * particle, -K_n delta_tau*, and the new spring in d_out. */
static vec3 coupling_soil_tangential(const sph_coupling *c, int64_t id, int b, vec3 n, vec3 urel, double fn, double kn,
                                     double dt, double d_out[3])
{
    vec3 d = v3(0, 0, 0);
    const int64_t base = id * SPH_COUPLING_MAX_PER_PARTICLE;
    for (int s = 0; s < SPH_COUPLING_MAX_PER_PARTICLE; s++)
        if (c->soil_hist_body[base + s] == b)
            d = v3_load(c->soil_hist_d[base + s]);
    d = v3_sub(d, v3_scale(n, v3_dot(d, n)));          /* onto the current tangent plane */
    vec3 ut = v3_sub(urel, v3_scale(n, v3_dot(urel, n))); /* eq. 22 */
    d = v3_axpy(dt, ut, d);                             /* eq. 23 */
    double len = v3_norm(d), lim = c->mu_phi * fn / kn;
    if (len > lim)                                      /* eq. 24: slip */
        d = len > 0.0 ? v3_scale(d, lim / len) : v3(0, 0, 0);
    v3_store(d, d_out);
    return v3_scale(d, -kn);                            /* eq. 25 */
}

void sph_coupling_mark(sph_coupling *c, const sph_cells *cells, int64_t n, const lahar_body_state *states)
{
    c->near_valid = 0;
    if (!c->near || c->nbody >= 32 || c->periodic[0] || c->periodic[1] || c->periodic[2] || n > c->pcap ||
        cells->periodic[0] || cells->periodic[1] || cells->periodic[2])
        return;
    memset(c->near, 0, (size_t)n * sizeof *c->near);
    const double support = c->k.support;
    const int d3 = cells->dim == 3;
    for (int b = 0; b < c->nbody; b++) {
        const lahar_body *body = &c->bodies[b];
        const int fixed = body->motion == LAHAR_MOTION_FIXED;
        const double *bx = !fixed && states ? states[b].x : body->x;
        double lo[3], hi[3];
        int all = 0;
        for (int a = 0; a < 3; a++) {
            lo[a] = (fixed ? c->box[b][a] : bx[a] - c->bound[b]) - support;
            hi[a] = (fixed ? c->box[b][3 + a] : bx[a] + c->bound[b]) + support;
            all |= !isfinite(lo[a]) || !isfinite(hi[a]);
        }
        const uint32_t bit = 1u << b;
        if (all) { /* no finite box: every particle may be near it */
            for (int64_t i = 0; i < n; i++)
                c->near[i] |= bit;
            continue;
        }
        /* the cells are bounded by the particles: a box that misses the grid marks nothing */
        int miss = 0;
        for (int a = 0; a < (d3 ? 3 : 2); a++)
            miss |= hi[a] < cells->lo[a] || lo[a] > cells->lo[a] + cells->nc[a] * cells->size[a];
        if (miss)
            continue;
        /* the cell of a coordinate is monotone in it (sph_cells_coord, clamped): a particle inside
         * [lo, hi] along an axis lies in a cell between those of lo and hi */
        const int x0 = sph_cells_coord(cells, 0, lo[0]), x1 = sph_cells_coord(cells, 0, hi[0]);
        const int y0 = sph_cells_coord(cells, 1, lo[1]), y1 = sph_cells_coord(cells, 1, hi[1]);
        const int z0 = d3 ? sph_cells_coord(cells, 2, lo[2]) : 0, z1 = d3 ? sph_cells_coord(cells, 2, hi[2]) : 0;
        for (int z = z0; z <= z1; z++)
            for (int y = y0; y <= y1; y++) {
                const int64_t row = ((int64_t)z * cells->nc[1] + y) * cells->nc[0];
                for (int64_t i = cells->start[row + x0]; i < cells->start[row + x1 + 1]; i++)
                    c->near[i] |= bit;
            }
    }
    c->near_valid = 1;
}

/* Where body b is now: the DEM node's state when it moves, the case's pose when it is fixed (fixed
 * bodies keep world-frame vertices, x = origin of that frame). */
typedef struct {
    const double *x, *q, *v, *w;
} coupling_pose;

static inline coupling_pose coupling_body_pose(const sph_coupling *c, const lahar_body_state *states, int b)
{
    const lahar_body *body = &c->bodies[b];
    const lahar_body_state *st = states && body->motion != LAHAR_MOTION_FIXED ? &states[b] : NULL;
    return st ? (coupling_pose){st->x, st->q, st->v, st->w} : (coupling_pose){body->x, body->q, body->v, body->w};
}

/* The constants of one evaluation. */
typedef struct {
    double dt, kn; /* the step and the penalty stiffness K_n (eq. 15) */
    double w0, hd; /* W(0) and h^D of eq. 17 */
} coupling_consts;

/* What one particle gathers over its contacts in one evaluation: the scalars, kept apart from the
 * arrays below so that the compiler holds them in registers (the arrays' addresses go to functions
 * of other files). */
typedef struct {
    int ns;        /* contacts written to its slots */
    int nh;        /* soil-DEM springs in contact now (sph_coupling_enable_soil) */
    int have_sbar; /* the soil ghosts' stresses are set (coupling_soil_ghost) */
    vec3 ftot;     /* the force on it from all of them */
    double drho_g; /* the ghosts' continuity term */
    double pbar;   /* the pressure around the particle, NaN until a ghost needs it */
} coupling_acc;

/* ... and the arrays, per contact or per spring. */
typedef struct {
    int hist_b[SPH_COUPLING_MAX_PER_PARTICLE]; /* the springs' bodies and values */
    double hist_d[SPH_COUPLING_MAX_PER_PARTICLE][3];
    /* ghost pressure per contact: normal, relative velocity, distance (< 0: no ghost), p_w */
    vec3 gn[SPH_COUPLING_MAX_PER_PARTICLE], gu[SPH_COUPLING_MAX_PER_PARTICLE];
    double gd[SPH_COUPLING_MAX_PER_PARTICLE], gp[SPH_COUPLING_MAX_PER_PARTICLE];
    /* soil ghosts (sph_coupling_set_soil_wall): the stresses, and their share of the velocity
     * gradient; set at the first soil ghost */
    double sbar[SPH_NSTRESS], sown[SPH_NSTRESS], lw[9];
} coupling_scratch;

/* The contact of a particle (an image of it) with a body's surface. */
typedef struct {
    vec3 nrm;  /* unit normal out of the body at the contact; zero on the core */
    vec3 xs;   /* the surface point (eq. 12) */
    double d;  /* signed distance to the surface (eq. 13) */
    int cross; /* the particle is behind the surface (or on the core) */
} coupling_surface;

/* The periodic images of a particle that may touch body b (sph_coupling_set_periodic): the
 * particle shifted by n whole periods towards the body, for every n along each periodic axis that
 * brings it within the body's range plus the support; the contact then lies on the body itself. A
 * body as long as the period along an axis (a channel's wall) overlaps its own images: it spans
 * that axis and has none along it, as without images; a body outside the period (plus the
 * support) is outside the domain and has none either. Returns n in [nlo, nhi] per axis. */
static inline void coupling_image_range(const sph_coupling *c, int b, const double *bx, vec3 xp, int nlo[3], int nhi[3])
{
    const double support = c->k.support;
    for (int a = 0; a < 3; a++) {
        nlo[a] = nhi[a] = 0;
        if (!c->periodic[a])
            continue;
        /* the range of the body along a: its world box when fixed (tight), else its sphere */
        const double *bb = c->box[b];
        int boxed = c->bodies[b].motion == LAHAR_MOTION_FIXED && isfinite(bb[a]) && isfinite(bb[3 + a]);
        double lo = boxed ? bb[a] : bx[a] - c->bound[b], hi = boxed ? bb[3 + a] : bx[a] + c->bound[b];
        double xa = v3_get(xp, a);
        const double plo = c->period_lo[a], phi = plo + c->period[a];
        if (hi - lo < c->period[a] && hi > plo - support && lo < phi + support && isfinite(xa)) {
            nlo[a] = (int)ceil((xa - hi - support) / c->period[a]);
            nhi[a] = (int)floor((xa - lo + support) / c->period[a]);
        }
    }
}

/* Culling, cheapest test first: the point xi is out of body b's reach (at least the support from
 * its surface) by a fixed body's tight world box or by any body's bounding sphere. A point culled
 * here is out of reach, so the tests' order and form change no result. */
static inline int coupling_culled(const sph_coupling *c, int b, vec3 xb, vec3 xi)
{
    const double support = c->k.support;
    if (c->bodies[b].motion == LAHAR_MOTION_FIXED) {
        const double *bb = c->box[b];
        if (xi.x < bb[0] - support || xi.x > bb[3] + support || xi.y < bb[1] - support || xi.y > bb[4] + support ||
            xi.z < bb[2] - support || xi.z > bb[5] + support)
            return 1;
    }
    const double reach = c->bound[b] + support;
    return v3_norm2(v3_sub(xi, xb)) > reach * reach;
}

/* The contact of the point xi with body b's surface (xb its position), past the culling; 0 when
 * the distance to the core, through the feature grids of big shapes (terrain, flumes), puts it out
 * of reach. Not inlined, nor is coupling_contact: they run for one culling test in ~50, and inlined
 * they crowd the registers of the culling loop (callgrind, debris_2d: 12 % more instructions in
 * the particle loop inlined, 6 % fewer than that loop written out in one function as it was). */
static __attribute__((noinline)) int coupling_find_surface(const sph_coupling *c, int b, coupling_pose pose, vec3 xb,
                                                           vec3 xi, coupling_surface *s)
{
    const lahar_body *body = &c->bodies[b];
    const double support = c->k.support, R = body->shape.radius;
    vec3 core = xb;
    double dc = geom_body_grids_core(&c->grids, b, &body->shape, pose.x, pose.q, xi, R + support, &core, NULL);
    /* deep inside: far from the surface */
    int inside = geom_point_in_core(&body->shape, body->convex, c->dim, pose.x, pose.q, xi);
    if (dc - R >= support && !inside)
        return 0;
    if (dc == DBL_MAX) /* inside a big closed core, far from every feature: no direction */
        dc = 0.0;
    s->cross = inside || dc < R;
    if (dc > 0.0) {
        s->nrm = v3_scale(v3_sub(xi, core), 1.0 / dc);
        s->d = dc - R; /* eq. 13, signed */
        if (inside) {
            s->nrm = v3_neg(s->nrm);
            s->d = -dc - R;
        }
    } else {
        s->nrm = v3(0, 0, 0); /* on the core: no direction to push; counted as a crossing */
        s->d = -R;
    }
    s->xs = v3_axpy(R, s->nrm, core); /* eq. 12 */
    return 1;
}

/* Water's wall shear m_i a_tau (eq. 19): the coefficient of u_rel at the viscous distance dv,
 * from the half-space model or eq. 17 as printed. */
static inline double coupling_wall_shear_coef(const sph_coupling *c, const sph_particles *p, int64_t i, int b,
                                              double dv, const coupling_consts *k)
{
    if (c->viscous == LAHAR_SPH_WALL_HALFSPACE)
        return 2.0 * c->mu / p->rho[i] * sph_coupling_body_halfspace_factor(c, b, dv);
    return 4.0 * p->m[i] / (3.0 * k->hd) * (2.0 * c->mu) / (4.0 * p->rho[i] * p->rho[i]) / dv *
           kernel_dwdr(&c->k, dv) / k->w0;
}

/* The soil ghost stress on a soil particle (sph_coupling_set_soil_wall); its push along n (fgn)
 * joins F_n of the friction cap, and its ghosts add to the particle's velocity gradient. */
static inline vec3 coupling_soil_ghost(const sph_coupling *c, const sph_particles *p, int64_t i,
                                       const coupling_surface *s, vec3 urel, double dv, coupling_acc *a,
                                       coupling_scratch *w, double *fgn)
{
    if (!a->have_sbar) {
        sph_ghost_soil_sigbar(c, p, i, w->sbar);
        for (int k = 0; k < SPH_NSTRESS; k++)
            w->sown[k] = p->sig[k][i];
        memset(w->lw, 0, sizeof w->lw);
        a->have_sbar = 1;
    }
    vec3 A;
    vec3 fg = v3_scale(sph_ghost_soil_accel(c, w->sown, w->sbar, p->rho[i], dv, s->nrm, &A), p->m[i]);
    *fgn = fmax(v3_dot(fg, s->nrm), 0.0);
    /* L_ab += sum_g V_g (v_g - v_i)_a (grad_i W_ig)_b with the ghosts' normal velocity the
     * wall's (free slip: their tangential velocity the particle's), v_g - v_i = -(u_rel.n) n,
     * grad_i W_ig = -F r_g: (u_rel.n) n_a A_b */
    const double un = v3_dot(urel, s->nrm), na[3] = {s->nrm.x, s->nrm.y, s->nrm.z}, ab[3] = {A.x, A.y, A.z};
    for (int r = 0; r < 3; r++)
        for (int q = 0; q < 3; q++)
            w->lw[r * 3 + q] += un * na[r] * ab[q];
    return fg;
}

/* The ghost wall pressure on a water particle (Adami et al. 2012, sph_wall_ghost.c): its
 * acceleration; the contact's normal, distance, velocity and wall pressure are kept for the
 * corner correction. The Riemann scheme adds this wall's dissipation to p_i (sph_riemann.h). */
static inline vec3 coupling_water_ghost(const sph_coupling *c, const sph_particles *p, int64_t i,
                                        const coupling_surface *s, vec3 urel, double dv, coupling_acc *a,
                                        coupling_scratch *w)
{
    const int ns = a->ns;
    double drw;
    if (a->pbar != a->pbar)
        a->pbar = sph_ghost_pbar(c, p, i);
    w->gp[ns] = c->riemann ? p->p[i] + sph_riemann_wall_dissipation(p->rho[i], v3_dot(urel, s->nrm), c->riemann_c0,
                                                                     c->riemann_eta)
                           : p->p[i];
    vec3 acc = sph_ghost_wall_accel(c, w->gp[ns], a->pbar, p->rho[i], dv, s->nrm, urel, &drw);
    a->drho_g += drw;
    w->gn[ns] = s->nrm;
    w->gd[ns] = dv;
    w->gu[ns] = urel;
    return acc;
}

/* The force of one contact on particle i (section 4: penalty eq. 14-15, wall shear eq. 16-19 or
 * the soil's friction of section 4.2, the ghost walls), added to a->ftot; the reaction (eq. 20)
 * goes to the particle's next slot. */
static __attribute__((noinline)) void coupling_contact(sph_coupling *c, const sph_particles *p, int64_t i, int b,
                                                       coupling_pose pose, const coupling_surface *s,
                                                       const coupling_consts *k, int soil, coupling_acc *a,
                                                       coupling_scratch *w)
{
    const int water = p->phase[i] == 0;
    const double delta = c->eps - s->d; /* eq. 14 */
    vec3 fn = delta > 0.0 ? v3_scale(s->nrm, k->kn * delta) : v3(0, 0, 0); /* eq. 15 */
    /* eq. 16: relative velocity to the body's surface at x_s */
    vec3 urel = v3_sub(v3(p->vx[i], p->vy[i], p->vz[i]),
                       v3_add(v3_load(pose.v), v3_cross(v3_load(pose.w), v3_sub(s->xs, v3_load(pose.x)))));
    double dv = fmax(s->d, 0.5 * c->eps); /* the viscous term's distance, kept off zero */
    vec3 ft = water ? v3_scale(urel, p->m[i] * coupling_wall_shear_coef(c, p, i, b, dv, k)) : v3(0, 0, 0);
    vec3 fg = v3(0, 0, 0);
    double fgn = 0.0;
    if (!water && c->soil_pressure == LAHAR_SPH_WALL_PRESSURE_GHOST && !s->cross && p->sig[0])
        fg = coupling_soil_ghost(c, p, i, s, urel, dv, a, w, &fgn);
    const double fn_tot = (delta > 0.0 ? k->kn * delta : 0.0) + fgn;
    if (soil && fn_tot > 0.0) {
        ft = coupling_soil_tangential(c, p->id[i], b, s->nrm, urel, fn_tot, k->kn, k->dt, w->hist_d[a->nh]);
        w->hist_b[a->nh++] = b;
    }
    vec3 f = v3_add(v3_add(fn, ft), fg);
    w->gd[a->ns] = -1.0;
    if (c->pressure == LAHAR_SPH_WALL_PRESSURE_GHOST && !s->cross && water) /* soil has eq. 22-27 */
        f = v3_axpy(p->m[i], coupling_water_ghost(c, p, i, s, urel, dv, a, w), f);
    a->ftot = v3_add(a->ftot, f);
    int64_t slot = i * SPH_COUPLING_MAX_PER_PARTICLE + a->ns;
    c->slot_body[slot] = s->cross ? -(b + 1) : b;
    sph_contact *ct = &c->slot[slot];
    v3_store(s->xs, ct->xs);
    v3_store(v3_neg(f), ct->force); /* eq. 20 */
    ct->delta = delta;
    ct->particle_id = p->id[i];
    a->ns++;
}

/* Ghost pressure at a concave corner of perpendicular bodies: the quadrant behind both once, not
 * twice (sph_coupling.h). */
static inline void coupling_ghost_corners(sph_coupling *c, const sph_particles *p, int64_t i, coupling_acc *a,
                                          coupling_scratch *w)
{
    for (int s1 = 0; s1 < a->ns; s1++)
        for (int s2 = 0; s2 < a->ns; s2++) {
            if (s1 == s2 || w->gd[s1] < 0.0 || w->gd[s2] < 0.0 || fabs(v3_dot(w->gn[s1], w->gn[s2])) >= 0.1)
                continue;
            double drc;
            vec3 fc = v3_scale(sph_ghost_corner_accel(c, w->gp[s1], a->pbar, p->rho[i], w->gd[s1], w->gn[s1], w->gd[s2],
                                                      w->gn[s2], w->gu[s1], w->gu[s2], &drc),
                               -p->m[i]);
            a->drho_g -= drc;
            /* eq. 20: wall s1 takes the reaction of the correction; of the half quadrant its
             * layers keep, the push along n_s2 is wall s2's (a ghost behind both walls pushes
             * across each wall's own plane), so that part of the reaction (-fc) moves over */
            sph_contact *ca = &c->slot[i * SPH_COUPLING_MAX_PER_PARTICLE + s1];
            sph_contact *cb = &c->slot[i * SPH_COUPLING_MAX_PER_PARTICLE + s2];
            vec3 fb = v3_scale(w->gn[s2], v3_dot(fc, w->gn[s2]));
            v3_store(v3_sub(v3_load(ca->force), v3_add(fc, fb)), ca->force);
            v3_store(v3_add(v3_load(cb->force), fb), cb->force);
            a->ftot = v3_add(a->ftot, fc);
        }
}

/* Particle i's contacts with every body in reach, each periodic image of it included. */
static inline void coupling_particle_contacts(sph_coupling *c, const sph_particles *p, int64_t i,
                                              const lahar_body_state *states, uint32_t near, const coupling_consts *k,
                                              int soil, coupling_acc *a, coupling_scratch *w)
{
    const vec3 xp = v3(p->x[i], p->y[i], p->z[i]);
    for (int b = 0; b < c->nbody && a->ns < SPH_COUPLING_MAX_PER_PARTICLE; b++) {
        if (!(near >> b & 1u)) /* sph_coupling_mark: this body is out of reach */
            continue;
        const coupling_pose pose = coupling_body_pose(c, states, b);
        const vec3 xb = v3_load(pose.x);
        int nlo[3], nhi[3];
        coupling_image_range(c, b, pose.x, xp, nlo, nhi);
        const int nx = nhi[0] - nlo[0] + 1, ny = nhi[1] - nlo[1] + 1, nimg = nx * ny * (nhi[2] - nlo[2] + 1);
        for (int img = 0; img < nimg && a->ns < SPH_COUPLING_MAX_PER_PARTICLE; img++) {
            /* without images (ix = iy = iz = 0) xi is the particle's position bit for bit; the
             * divisions only where there are several images (most particles have one) */
            const int ix = nlo[0] + (nimg > 1 ? img % nx : 0), iy = nlo[1] + (nimg > 1 ? img / nx % ny : 0),
                      iz = nlo[2] + (nimg > 1 ? img / (nx * ny) : 0);
            vec3 xi = v3(xp.x - ix * c->period[0], xp.y - iy * c->period[1], xp.z - iz * c->period[2]);
            if (coupling_culled(c, b, xb, xi))
                continue;
            coupling_surface s;
            if (coupling_find_surface(c, b, pose, xb, xi, &s))
                coupling_contact(c, p, i, b, pose, &s, k, soil, a, w);
        }
    }
}

/* Particle i's share of the evaluation: its slot count, soil velocity gradient and springs, and
 * the accelerations and continuity term on it. */
static inline void coupling_particle_finish(sph_coupling *c, sph_particles *p, int64_t i, int soil,
                                            const coupling_acc *a, const coupling_scratch *w)
{
    c->slot_n[i] = a->ns;
    if (c->soil_lw_on) {
        c->soil_lw_on[i] = (unsigned char)a->have_sbar;
        if (a->have_sbar)
            memcpy(c->soil_lw[i], w->lw, sizeof w->lw);
    }
    if (soil) { /* the springs of the pairs in contact now; the others are released */
        const int64_t base = p->id[i] * SPH_COUPLING_MAX_PER_PARTICLE;
        for (int s = 0; s < SPH_COUPLING_MAX_PER_PARTICLE; s++) {
            c->soil_hist_body[base + s] = s < a->nh ? w->hist_b[s] : -1;
            if (s < a->nh)
                memcpy(c->soil_hist_d[base + s], w->hist_d[s], sizeof w->hist_d[s]);
        }
    }
    if (a->ns == 0 && a->drho_g == 0.0) /* far from every body (most particles): nothing to add */
        return;
    double inv_m = 1.0 / p->m[i];
    p->drho[i] += a->drho_g;
    p->ax[i] += a->ftot.x * inv_m;
    p->ay[i] += a->ftot.y * inv_m;
    p->az[i] += a->ftot.z * inv_m;
}

/* Serial, in particle order: the contacts per body (crossings noted, the first one kept for the
 * message), their list by body, and each body's resultant force and torque (eq. 21 with the torque
 * as r x F). Returns -1 when the list cannot grow. */
static int coupling_gather(sph_coupling *c, int64_t n, const lahar_body_state *states)
{
    for (int b = 0; b < c->nbody; b++) {
        c->force[b][0] = c->force[b][1] = c->force[b][2] = 0.0;
        c->torque[b][0] = c->torque[b][1] = c->torque[b][2] = 0.0;
        c->body_fill[b] = 0;
    }
    int64_t total = 0;
    c->crossings = 0;
    c->cross_body = -1;
    c->cross_particle_id = -1;
    c->cross_depth = 0.0;
    for (int64_t i = 0; i < n; i++)
        for (int s = 0; s < c->slot_n[i]; s++) {
            int64_t k = i * SPH_COUPLING_MAX_PER_PARTICLE + s;
            int b = c->slot_body[k];
            if (b < 0) {
                b = -b - 1;
                c->slot_body[k] = b;
                if (c->crossings++ == 0) {
                    c->cross_body = b;
                    c->cross_particle_id = c->slot[k].particle_id;
                    c->cross_depth = c->slot[k].delta - c->eps; /* -d: depth inside the surface */
                }
            }
            c->body_fill[b]++;
            total++;
        }
    if (total > c->contacts_cap) {
        int64_t cap = c->contacts_cap;
        while (cap < total)
            cap *= 2;
        sph_contact *nc = realloc(c->contacts, (size_t)cap * sizeof *nc);
        if (!nc)
            return -1;
        c->contacts = nc;
        c->contacts_cap = cap;
    }
    c->body_start[0] = 0;
    for (int b = 0; b < c->nbody; b++) {
        c->body_start[b + 1] = c->body_start[b] + c->body_fill[b];
        c->body_fill[b] = c->body_start[b];
    }
    for (int64_t i = 0; i < n; i++)
        for (int s = 0; s < c->slot_n[i]; s++) {
            int64_t k = i * SPH_COUPLING_MAX_PER_PARTICLE + s;
            int b = c->slot_body[k];
            const sph_contact *ct = &c->slot[k];
            c->contacts[c->body_fill[b]++] = *ct;
            vec3 f = v3_load(ct->force), r = v3_sub(v3_load(ct->xs), v3_load(coupling_body_pose(c, states, b).x));
            vec3 t = v3_cross(r, f);
            for (int a = 0; a < 3; a++) {
                c->force[b][a] += v3_get(f, a);
                c->torque[b][a] += v3_get(t, a);
            }
        }
    c->ncontacts = total;
    return 0;
}

int64_t sph_coupling_apply(sph_coupling *c, sph_particles *p, const lahar_body_state *states, double dt)
{
    const int64_t n = p->n;
    /* eq. 15: K_n = 0.1 m_min / dt^2; with kn_dt > 0 the acoustic step instead (sph_coupling.h) */
    const double dtk = c->kn_dt > 0.0 ? c->kn_dt : dt;
    const coupling_consts k = {.dt = dt, .kn = 0.1 * c->m_min / (dtk * dtk), .w0 = kernel_w(&c->k, 0.0),
                               .hd = pow(c->k.h, c->dim)};
    c->kn = k.kn;
    if (n > c->pcap)
        return -1;

    const int near_valid = c->near_valid && c->nbody < 32;
    c->near_valid = 0; /* the marks serve this evaluation only */
#pragma omp parallel for schedule(dynamic, SPH_OMP_CHUNK) if (n >= SPH_OMP_MIN_HEAVY)
    for (int64_t i = 0; i < n; i++) {
        /* soil-DEM springs of this evaluation (sph_coupling_enable_soil) */
        const int soil = p->phase[i] != 0 && c->soil_hist_body;
        coupling_acc a = {.ns = 0, .nh = 0, .have_sbar = 0, .ftot = v3(0, 0, 0), .drho_g = 0.0, .pbar = NAN};
        coupling_scratch w;
        coupling_particle_contacts(c, p, i, states, near_valid ? c->near[i] : ~0u, &k, soil, &a, &w);
        coupling_ghost_corners(c, p, i, &a, &w);
        coupling_particle_finish(c, p, i, soil, &a, &w);
    }
    if (coupling_gather(c, n, states))
        return -1;
    return c->crossings;
}
