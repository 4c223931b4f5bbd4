/* SPH-DEM coupling (sph_coupling.h; paper 000 section 4). */
#include "sph_coupling.h"
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "geometry.h"
#include "vec.h"

/* G(d) = sum over ghost layers at depths s_k = (k + 1/2) dx behind the surface of
 * (1 + s_k/d) dx int_layer W'(r)/r r^2/(r^2 + eta^2) dA, for a particle at distance d in front of it.
 * The layers mirror the fluid lattice (first fluid row at dx/2 in front of the surface, first
 * ghost layer at dx/2 behind it), so for a linear velocity field the fluid rows and the ghosts
 * cancel like a full lattice does; a continuous half-space integral instead leaves 4 % of the wall
 * shear as a spurious force dipole on the first two rows (cubic, h = 1.3 dx). Within a layer the
 * integral is continuous (midpoint rule), since the fluid slides along the wall. */
static double ghost_layers(const kernel *k, int dim, double d, double dx)
{
    const int nt = 2000;
    double S = k->support, eta2 = 0.01 * k->h * k->h, dt = S / nt, g = 0.0;
    for (int l = 0;; l++) {
        double s = (l + 0.5) * dx, y = d + s;
        if (y >= S)
            break;
        double layer = 0.0;
        for (int b = 0; b < nt; b++) {
            double t = (b + 0.5) * dt, r2 = t * t + y * y, r = sqrt(r2);
            if (r >= S)
                break;
            double f = kernel_dwdr(k, r) / r * r2 / (r2 + eta2);
            layer += dim == 2 ? 2.0 * f : 2.0 * M_PI * t * f; /* 2D: both sides of the normal; 3D: ring */
        }
        g += (1.0 + s / d) * layer * dt * dx;
    }
    return g;
}

double sph_coupling_halfspace_factor(const sph_coupling *c, double d)
{
    double u = (d - c->gtab_d0) / c->gtab_dd;
    if (!(u > 0.0))
        return c->gtab[0];
    if (u >= SPH_COUPLING_GTAB)
        return 0.0;
    int i = (int)u;
    double f = u - i;
    return (1.0 - f) * c->gtab[i] + f * c->gtab[i + 1];
}

int sph_coupling_init(sph_coupling *c, int dim, int nbody, const lahar_body *bodies, const kernel *k, double dx,
                      double m_sph, double mu, sph_wall_viscous viscous, int64_t particle_cap)
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
    c->grid = calloc((size_t)nb, sizeof *c->grid);
    c->box = calloc((size_t)nb, sizeof *c->box);
    c->has_grid = calloc((size_t)nb, sizeof *c->has_grid);
    c->force = calloc((size_t)nb, sizeof *c->force);
    c->torque = calloc((size_t)nb, sizeof *c->torque);
    c->body_start = calloc((size_t)nb + 1, sizeof *c->body_start);
    c->body_fill = calloc((size_t)nb, sizeof *c->body_fill);
    c->slot_n = calloc((size_t)c->pcap, sizeof *c->slot_n);
    c->slot_body = calloc((size_t)c->pcap * SPH_COUPLING_MAX_PER_PARTICLE, sizeof *c->slot_body);
    c->slot = calloc((size_t)c->pcap * SPH_COUPLING_MAX_PER_PARTICLE, sizeof *c->slot);
    c->contacts_cap = 1024;
    c->contacts = calloc((size_t)c->contacts_cap, sizeof *c->contacts);
    if (!c->bound || !c->box || !c->grid || !c->has_grid || !c->force || !c->torque || !c->body_start || !c->body_fill || !c->slot_n || !c->slot_body ||
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
        if (s->nv + s->ne + s->nf > SPH_COUPLING_GRID_FEATURES) {
            if (geom_feature_grid_build(&c->grid[b], s) != 0) {
                sph_coupling_free(c);
                return -1;
            }
            c->has_grid[b] = 1;
        }
    }
    /* the half-space factor, tabulated from eps/2 (closest a particle is let near) to the support */
    c->gtab_d0 = 0.5 * c->eps;
    c->gtab_dd = (k->support - c->gtab_d0) / SPH_COUPLING_GTAB;
    for (int i = 0; i <= SPH_COUPLING_GTAB; i++)
        c->gtab[i] = ghost_layers(k, dim, c->gtab_d0 + i * c->gtab_dd, dx);
    return 0;
}

void sph_coupling_free(sph_coupling *c)
{
    for (int b = 0; c->has_grid && b < c->nbody; b++)
        if (c->has_grid[b])
            geom_feature_grid_free(&c->grid[b]);
    free(c->grid);
    free(c->box);
    free(c->has_grid);
    free(c->bound);
    free(c->force);
    free(c->torque);
    free(c->body_start);
    free(c->body_fill);
    free(c->slot_n);
    free(c->slot_body);
    free(c->slot);
    free(c->contacts);
    free(c->soil_hist_body);
    free(c->soil_hist_d);
    memset(c, 0, sizeof *c);
}

int sph_coupling_enable_soil(sph_coupling *c, double mu_phi)
{
    const size_t n = (size_t)c->pcap * SPH_COUPLING_MAX_PER_PARTICLE;
    free(c->soil_hist_body);
    free(c->soil_hist_d);
    c->soil_hist_body = malloc(n * sizeof *c->soil_hist_body);
    c->soil_hist_d = calloc(n, sizeof *c->soil_hist_d);
    if (!c->soil_hist_body || !c->soil_hist_d) {
        free(c->soil_hist_body), free(c->soil_hist_d);
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

/* 1 when p lies inside the closed core: a convex polyhedron (all face planes) in 3D, a closed
 * polygon (crossing number in the x-y plane) in 2D. Open or non-convex 3D cores: 0. */
static int inside_core(const lahar_body *body, const double x[3], const double q[4], vec3 p, int dim)
{
    const lahar_shape *s = &body->shape;
    if (dim == 3) {
        if (s->nf < 4 || !body->convex)
            return 0;
        quat qq = q_load(q);
        for (int f = 0; f < s->nf; f++) {
            vec3 n = q_rotate(qq, geom_face_normal(s, f));
            vec3 a = geom_world_vertex(s, x, q, s->face_v[s->face_start[f]]);
            if (v3_dot(v3_sub(p, a), n) >= 0.0)
                return 0;
        }
        return 1;
    }
    if (s->nv < 3 || s->ne != s->nv)
        return 0;
    int in = 0;
    for (int e = 0; e < s->ne; e++) {
        vec3 a = geom_world_vertex(s, x, q, s->e[e][0]), b = geom_world_vertex(s, x, q, s->e[e][1]);
        if ((a.y > p.y) != (b.y > p.y)) {
            double xc = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
            if (p.x < xc)
                in = !in;
        }
    }
    return in;
}

int64_t sph_coupling_apply(sph_coupling *c, sph_particles *p, const lahar_body_state *states, double dt)
{
    const int64_t n = p->n;
    const double support = c->k.support;
    /* eq. 15: K_n = 0.1 m_min / dt^2 */
    const double kn = 0.1 * c->m_min / (dt * dt);
    c->kn = kn;
    const double w0 = kernel_w(&c->k, 0.0), hd = pow(c->k.h, c->dim);
    if (n > c->pcap)
        return -1;

#pragma omp parallel for schedule(static) if (n >= SPH_OMP_MIN_HEAVY)
    for (int64_t i = 0; i < n; i++) {
        int ns = 0;
        vec3 xi = v3(p->x[i], p->y[i], p->z[i]);
        vec3 ftot = v3(0, 0, 0);
        /* soil-DEM springs of this evaluation (sph_coupling_enable_soil) */
        const int soil = p->phase[i] != 0 && c->soil_hist_body;
        int nh = 0, hist_b[SPH_COUPLING_MAX_PER_PARTICLE];
        double hist_d[SPH_COUPLING_MAX_PER_PARTICLE][3];
        for (int b = 0; b < c->nbody && ns < SPH_COUPLING_MAX_PER_PARTICLE; b++) {
            const lahar_body *body = &c->bodies[b];
            const lahar_body_state *st = states && body->motion != LAHAR_MOTION_FIXED ? &states[b] : NULL;
            const double *bx = st ? st->x : body->x, *bq = st ? st->q : body->q;
            const double *bv = st ? st->v : body->v, *bw = st ? st->w : body->w;
            vec3 xb = v3_load(bx);
            const double R = body->shape.radius;
            /* bounding sphere; fixed bodies keep world-frame vertices (x = origin of that frame) */
            if (v3_norm(v3_sub(xi, xb)) > c->bound[b] + support)
                continue;
            if (body->motion == LAHAR_MOTION_FIXED) {
                const double *bb = c->box[b];
                if (xi.x < bb[0] - support || xi.x > bb[3] + support || xi.y < bb[1] - support ||
                    xi.y > bb[4] + support || xi.z < bb[2] - support || xi.z > bb[5] + support)
                    continue;
            }
            vec3 core = xb;
            /* big shapes (terrain, flumes): only the features near the particle */
            double dc = c->has_grid[b] ? geom_point_body_core_near(&c->grid[b], &body->shape, bx, bq, xi, R + support,
                                                                   &core, NULL)
                                       : geom_point_body_core(&body->shape, bx, bq, xi, &core, NULL);
            int inside = inside_core(body, bx, bq, xi, c->dim); /* deep inside: far from the surface */
            if (dc - R >= support && !inside)
                continue;
            if (dc == DBL_MAX) /* inside a big closed core, far from every feature: no direction */
                dc = 0.0;
            int cross = inside || dc < R;
            vec3 nrm;
            double d;
            if (dc > 0.0) {
                nrm = v3_scale(v3_sub(xi, core), 1.0 / dc);
                d = dc - R; /* eq. 13, signed */
                if (inside) {
                    nrm = v3_neg(nrm);
                    d = -dc - R;
                }
            } else {
                nrm = v3(0, 0, 0); /* on the core: no direction to push; counted as a crossing */
                d = -R;
            }
            vec3 xs = v3_axpy(R, nrm, core);         /* eq. 12 */
            double delta = c->eps - d;               /* eq. 14 */
            vec3 fn = delta > 0.0 ? v3_scale(nrm, kn * delta) : v3(0, 0, 0); /* eq. 15 */
            /* eq. 16: relative velocity to the body's surface at x_s */
            vec3 urel = v3_sub(v3(p->vx[i], p->vy[i], p->vz[i]),
                               v3_add(v3_load(bv), v3_cross(v3_load(bw), v3_sub(xs, xb))));
            double dv = fmax(d, 0.5 * c->eps); /* the viscous term's distance, kept off zero */
            double coef;
            if (c->viscous == SPH_WALL_VISCOUS_HALFSPACE)
                coef = 2.0 * c->mu / p->rho[i] * sph_coupling_halfspace_factor(c, dv);
            else /* eq. 17 as printed */
                coef = 4.0 * p->m[i] / (3.0 * hd) * (2.0 * c->mu) / (4.0 * p->rho[i] * p->rho[i]) / dv *
                       kernel_dwdr(&c->k, dv) / w0;
            /* m_i a_tau (eq. 19) for water; soil: the frictional force of section 4.2 */
            vec3 ft = p->phase[i] == 0 ? v3_scale(urel, p->m[i] * coef) : v3(0, 0, 0);
            if (soil && delta > 0.0) {
                ft = coupling_soil_tangential(c, p->id[i], b, nrm, urel, kn * delta, kn, dt, hist_d[nh]);
                hist_b[nh++] = b;
            }
            vec3 f = v3_add(fn, ft);
            ftot = v3_add(ftot, f);
            int64_t k = i * SPH_COUPLING_MAX_PER_PARTICLE + ns;
            c->slot_body[k] = cross ? -(b + 1) : b;
            sph_contact *ct = &c->slot[k];
            v3_store(xs, ct->xs);
            v3_store(v3_neg(f), ct->force); /* eq. 20 */
            ct->delta = delta;
            ct->particle_id = p->id[i];
            ns++;
        }
        c->slot_n[i] = ns;
        if (soil) { /* the springs of the pairs in contact now; the others are released */
            const int64_t base = p->id[i] * SPH_COUPLING_MAX_PER_PARTICLE;
            for (int s = 0; s < SPH_COUPLING_MAX_PER_PARTICLE; s++) {
                c->soil_hist_body[base + s] = s < nh ? hist_b[s] : -1;
                if (s < nh)
                    memcpy(c->soil_hist_d[base + s], hist_d[s], sizeof hist_d[s]);
            }
        }
        double inv_m = 1.0 / p->m[i];
        p->ax[i] += ftot.x * inv_m;
        p->ay[i] += ftot.y * inv_m;
        p->az[i] += ftot.z * inv_m;
    }

    /* serial, in particle order: per-body resultants, contact list, crossings */
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
            const double *bx = states && c->bodies[b].motion != LAHAR_MOTION_FIXED ? states[b].x : c->bodies[b].x;
            vec3 f = v3_load(ct->force), r = v3_sub(v3_load(ct->xs), v3_load(bx));
            vec3 t = v3_cross(r, f); /* eq. 21 with the torque as r x F */
            for (int a = 0; a < 3; a++) {
                c->force[b][a] += v3_get(f, a);
                c->torque[b][a] += v3_get(t, a);
            }
        }
    c->ncontacts = total;
    return c->crossings;
}
