/* Pressure probes and level gauges (sph_probes.h). */
#include "sph_probes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry.h"
#include "sph_gauges.h"
#include "vec.h"

#define SPH_PROBE_DRY_FLUID KERNEL_SURFACE_FRACTION /* kernel.h */
#define SPH_PROBE_LEVEL_POINTS 8 /* line points per dx */
#define SPH_PROBE_DRY_WALL 0.1  /* wetted: ~1/2 on a flat wall, ~1/4 in a 90 degree corner */

/* Points of a sensor of diameter size about x with normal n (world, scene pose), at most dx/4
 * apart (midpoints of equal parts of the segment; in 3D the points of a square grid inside the
 * disc), each projected onto the body's surface. Returns the count (>= 1). */
static int probe_points(const lahar_case *c, const lahar_probe *p, double (*out)[3], double (*nout)[3])
{
    const int dim = c->dim;
    vec3 x = v3_load(p->x), n = v3_load(p->n);
    int m = 0;
    if (p->size <= 0.0) {
        out[0][0] = x.x, out[0][1] = x.y, out[0][2] = x.z;
        memcpy(nout[0], p->n, sizeof nout[0]);
        return 1;
    }
    int k = (int)ceil(p->size / (0.25 * c->sph_dx));
    if (dim == 2) {
        if (k < 2)
            k = 2;
        if (k > SPH_PROBE_MAX_POINTS)
            k = SPH_PROBE_MAX_POINTS;
        vec3 t = v3(-n.y, n.x, 0.0);
        for (int i = 0; i < k; i++) {
            vec3 q = v3_axpy(p->size * ((i + 0.5) / k - 0.5), t, x);
            out[m][0] = q.x, out[m][1] = q.y, out[m][2] = 0.0, m++;
        }
    } else {
        vec3 a = fabs(n.x) < 0.9 ? v3(1, 0, 0) : v3(0, 1, 0);
        vec3 t1 = v3_normalize(v3_cross(n, a)), t2 = v3_cross(n, t1);
        if (k < 2)
            k = 2;
        while (k * k > SPH_PROBE_MAX_POINTS)
            k--;
        double r = 0.5 * p->size;
        for (int i = 0; i < k; i++)
            for (int j = 0; j < k; j++) {
                double u = p->size * ((i + 0.5) / k - 0.5), v = p->size * ((j + 0.5) / k - 0.5);
                if (u * u + v * v > r * r)
                    continue;
                vec3 q = v3_axpy(u, t1, v3_axpy(v, t2, x));
                out[m][0] = q.x, out[m][1] = q.y, out[m][2] = q.z, m++;
            }
        if (m == 0) {
            out[0][0] = x.x, out[0][1] = x.y, out[0][2] = x.z;
            m = 1;
        }
    }
    /* onto the surface (curved bodies), with the normal there */
    const lahar_body *bd = &c->bodies[p->body];
    for (int i = 0; i < m; i++) {
        vec3 cp;
        int feat;
        vec3 q = v3_load(out[i]);
        double d = geom_point_body_core(&bd->shape, bd->x, bd->q, q, &cp, &feat);
        vec3 nn = d > 0.0 ? v3_scale(v3_sub(q, cp), 1.0 / d) : n;
        if (v3_dot(nn, n) < 0.0) /* a point that fell inside the core's shell: keep the sensor's side */
            nn = n;
        vec3 s = v3_axpy(bd->shape.radius, nn, cp);
        out[i][0] = s.x, out[i][1] = s.y, out[i][2] = dim == 3 ? s.z : 0.0;
        nout[i][0] = nn.x, nout[i][1] = nn.y, nout[i][2] = dim == 3 ? nn.z : 0.0;
    }
    return m;
}

int sph_probes_init(sph_probes *pr, const lahar_case *c)
{
    memset(pr, 0, sizeof *pr);
    const int n = c->nprobe;
    double(*tx)[3] = malloc(SPH_PROBE_MAX_POINTS * sizeof *tx), (*tn)[3] = malloc(SPH_PROBE_MAX_POINTS * sizeof *tn);
    pr->pt0 = calloc((size_t)n + 1, sizeof *pr->pt0);
    pr->body = calloc((size_t)n, sizeof *pr->body);
    pr->rate = calloc((size_t)n, sizeof *pr->rate);
    pr->next_slot = calloc((size_t)n, sizeof *pr->next_slot);
    pr->v0 = calloc((size_t)n + 1, sizeof *pr->v0);
    pr->target = calloc((size_t)n, sizeof *pr->target);
    for (int k = 0; k < n && pr->v0; k++)
        pr->v0[k + 1] = pr->v0[k] + lahar_probe_nvalues(c->probes[k].kind);
    pr->value = pr->v0 ? calloc((size_t)pr->v0[n] + 1, sizeof *pr->value) : NULL;
    pr->due = calloc((size_t)n, sizeof *pr->due);
    pr->xl = malloc((size_t)n * SPH_PROBE_MAX_POINTS * sizeof *pr->xl);
    pr->nl = malloc((size_t)n * SPH_PROBE_MAX_POINTS * sizeof *pr->nl);
    pr->kind = calloc((size_t)n, sizeof *pr->kind);
    pr->l0 = calloc((size_t)n + 1, sizeof *pr->l0);
    pr->lstep = calloc((size_t)n, sizeof *pr->lstep);
    /* level gauges: points dx / SPH_PROBE_LEVEL_POINTS apart from the floor to the top */
    int64_t nlp = 0;
    const double lstep = c->sph_dx / SPH_PROBE_LEVEL_POINTS;
    for (int k = 0; k < n && pr->l0; k++) {
        const lahar_probe *p = &c->probes[k];
        pr->l0[k] = (int)nlp;
        if (p->kind == LAHAR_PROBE_LEVEL)
            nlp += (int64_t)ceil((p->top - p->x[c->dim - 1]) / lstep) + 1;
    }
    if (pr->l0 && nlp < INT32_MAX)
        pr->l0[n] = (int)nlp;
    pr->lphi = nlp < INT32_MAX ? malloc((size_t)(nlp > 0 ? nlp : 1) * sizeof *pr->lphi) : NULL;
    if (!tx || !tn || !pr->pt0 || !pr->body || !pr->rate || !pr->next_slot || !pr->value || !pr->due || !pr->xl ||
        !pr->v0 || !pr->target ||
        !pr->nl || !pr->kind || !pr->l0 || !pr->lstep || !pr->lphi) {
        free(tx), free(tn);
        sph_probes_free(pr);
        return -1;
    }
    pr->n = n;
    int m = 0;
    for (int k = 0; k < n; k++) {
        const lahar_probe *p = &c->probes[k];
        pr->pt0[k] = m;
        pr->body[k] = p->body;
        pr->rate[k] = p->rate;
        pr->kind[k] = p->kind;
        pr->lstep[k] = lstep;
        pr->target[k] = -1;
        if (p->body < 0) {
            memcpy(pr->xl[m], p->x, sizeof pr->xl[m]);
            memset(pr->nl[m], 0, sizeof pr->nl[m]);
            m++;
            continue;
        }
        const lahar_body *bd = &c->bodies[p->body];
        int np = probe_points(c, p, tx, tn);
        quat q = q_load(bd->q);
        for (int i = 0; i < np; i++, m++) {
            vec3 xl = q_rotate_inv(q, v3_sub(v3_load(tx[i]), v3_load(bd->x)));
            vec3 nl = q_rotate_inv(q, v3_load(tn[i]));
            pr->xl[m][0] = xl.x, pr->xl[m][1] = xl.y, pr->xl[m][2] = xl.z;
            pr->nl[m][0] = nl.x, pr->nl[m][1] = nl.y, pr->nl[m][2] = nl.z;
        }
    }
    pr->pt0[n] = m;
    pr->npts = m;
    free(tx), free(tn);
    return 0;
}

void sph_probes_free(sph_probes *pr)
{
    free(pr->pt0), free(pr->body), free(pr->rate), free(pr->next_slot), free(pr->value), free(pr->due);
    free(pr->xl), free(pr->nl), free(pr->kind), free(pr->l0), free(pr->lphi), free(pr->lstep);
    free(pr->v0), free(pr->target);
    memset(pr, 0, sizeof *pr);
}

/* Cell range [lo, hi] along axis a of the support about x (clamped: the edge cells hold every
 * particle beyond them); a periodic axis is walked whole, with minimum images. */
static void probe_cell_range(const sph_cells *cl, int a, double x, double S, int *lo, int *hi)
{
    if (a >= cl->dim) {
        *lo = *hi = 0;
        return;
    }
    if (cl->periodic[a]) {
        *lo = 0, *hi = cl->nc[a] - 1;
        return;
    }
    *lo = sph_cells_coord(cl, a, x - S);
    *hi = sph_cells_coord(cl, a, x + S);
}

double sph_probes_point(const sph_fluid *f, const double x[3], int wall)
{
    const sph_cells *cl = &f->cells;
    const sph_particles *p = &f->p;
    const kernel *k = &f->k;
    const double S = k->support, S2 = S * S;
    const double *b = f->prm.body_force;
    int lo[3], hi[3];
    for (int a = 0; a < 3; a++)
        probe_cell_range(cl, a, x[a], S, &lo[a], &hi[a]);
    double sw = 0.0, svw = 0.0, spw = 0.0, sg = 0.0;
    for (int cz = lo[2]; cz <= hi[2]; cz++)
        for (int cy = lo[1]; cy <= hi[1]; cy++) {
            int64_t row = ((int64_t)cz * cl->nc[1] + cy) * cl->nc[0];
            for (int64_t j = cl->start[row + lo[0]]; j < cl->start[row + hi[0] + 1]; j++) {
                if (p->phase[j] != 0)
                    continue;
                double r[3] = {x[0] - p->x[j], x[1] - p->y[j], cl->dim == 3 ? x[2] - p->z[j] : 0.0};
                for (int a = 0; a < cl->dim; a++)
                    if (cl->periodic[a]) {
                        double L = cl->hi[a] - cl->lo[a];
                        r[a] -= L * floor(r[a] / L + 0.5);
                    }
                double r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
                if (r2 >= S2)
                    continue;
                double w = kernel_w(k, sqrt(r2)), pj = sph_fluid_pressure(&f->prm, p->rho[j]);
                double vw = p->m[j] / p->rho[j] * w;
                svw += vw;
                if (wall) { /* Adami et al. 2012 eq. 27 */
                    sw += w;
                    spw += pj * w;
                    sg += p->rho[j] * (b[0] * r[0] + b[1] * r[1] + b[2] * r[2]) * w;
                } else {
                    spw += pj * vw;
                }
            }
        }
    if (wall)
        return svw >= SPH_PROBE_DRY_WALL && sw > 0.0 ? (spw + sg) / sw : 0.0;
    return svw >= SPH_PROBE_DRY_FLUID ? spw / svw : 0.0;
}

double sph_probes_level(const sph_fluid *f, const double foot[3], int npt, double step, double *phi)
{
    const sph_cells *cl = &f->cells;
    const sph_particles *p = &f->p;
    const kernel *k = &f->k;
    const int dim = cl->dim, v = dim - 1;
    const double S = k->support, S2 = S * S, z0 = foot[v], ztop = z0 + (npt - 1) * step;
    int lo[3], hi[3];
    for (int a = 0; a < 3; a++)
        probe_cell_range(cl, a, foot[a], S, &lo[a], &hi[a]);
    lo[v] = sph_cells_coord(cl, v, z0 - S);
    hi[v] = sph_cells_coord(cl, v, ztop + S);
    for (int i = 0; i < npt; i++)
        phi[i] = 0.0;
    for (int cz = lo[2]; cz <= hi[2]; cz++)
        for (int cy = lo[1]; cy <= hi[1]; cy++) {
            int64_t row = ((int64_t)cz * cl->nc[1] + cy) * cl->nc[0];
            for (int64_t j = cl->start[row + lo[0]]; j < cl->start[row + hi[0] + 1]; j++) {
                if (p->phase[j] != 0)
                    continue;
                const double xj[3] = {p->x[j], p->y[j], dim == 3 ? p->z[j] : 0.0};
                double rh2 = 0.0;
                for (int a = 0; a < v; a++) {
                    double r = foot[a] - xj[a];
                    if (cl->periodic[a]) {
                        double L = cl->hi[a] - cl->lo[a];
                        r -= L * floor(r / L + 0.5);
                    }
                    rh2 += r * r;
                }
                if (rh2 >= S2)
                    continue;
                const double vj = p->m[j] / p->rho[j];
                kernel_line_add(k, rh2, xj[v], vj, z0, step, npt, phi);
                /* its mirror image below the floor (z0 - (zj - z0)): the half space the floor cuts off */
                if (xj[v] >= z0) /* a particle below the floor has no image */
                    kernel_line_add(k, rh2, 2.0 * z0 - xj[v], vj, z0, step, npt, phi);
            }
        }
    /* the first crossing going up from the floor: the top of the water column standing on it */
    return kernel_line_crossing(phi, npt, step, SPH_PROBE_DRY_FLUID, 0);
}

int sph_probes_sample(sph_probes *pr, const sph_fluid *f, const lahar_case *c, const lahar_body_state *states,
                      double t)
{
    int ndue = 0;
    for (int k = 0; k < pr->n; k++) {
        pr->due[k] = 0;
        if (pr->rate[k] > 0.0) {
            /* the first step at or after each multiple of 1/rate (as forces_interval) */
            double dt = 1.0 / pr->rate[k];
            if (t < (double)pr->next_slot[k] * dt * (1.0 - 1e-12) - 1e-300)
                continue;
            pr->next_slot[k] = (int64_t)floor(t / dt * (1.0 + 1e-12)) + 1;
        }
        pr->due[k] = 1;
        ndue++;
        double *val = pr->value + pr->v0[k];
        if (pr->kind[k] == LAHAR_PROBE_TRACKER) {
            if (pr->target[k] < 0)
                pr->target[k] = sph_gauges_nearest(f, c->probes[k].x);
            sph_gauges_tracker(f, pr->target[k], val);
            continue;
        }
        if (pr->kind[k] == LAHAR_PROBE_CONTROL_VOLUME) {
            sph_gauges_control_volume(f, &c->probes[k], c, states, val);
            continue;
        }
        if (pr->kind[k] == LAHAR_PROBE_LEVEL) {
            val[0] = sph_probes_level(f, pr->xl[pr->pt0[k]], pr->l0[k + 1] - pr->l0[k], pr->lstep[k],
                                            pr->lphi + pr->l0[k]);
            continue;
        }
        const int b = pr->body[k];
        double sum = 0.0;
        for (int i = pr->pt0[k]; i < pr->pt0[k + 1]; i++) {
            double xw[3];
            if (b < 0) {
                memcpy(xw, pr->xl[i], sizeof xw);
            } else {
                const double *bx = states ? states[b].x : c->bodies[b].x, *bq = states ? states[b].q : c->bodies[b].q;
                vec3 w = v3_add(v3_load(bx), q_rotate(q_load(bq), v3_load(pr->xl[i])));
                xw[0] = w.x, xw[1] = w.y, xw[2] = c->dim == 3 ? w.z : 0.0;
            }
            sum += sph_probes_point(f, xw, b >= 0);
        }
        val[0] = sum / (double)(pr->pt0[k + 1] - pr->pt0[k]);
    }
    return ndue;
}
