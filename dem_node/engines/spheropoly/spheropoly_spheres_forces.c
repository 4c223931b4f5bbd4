/* The sphere fast path's contact forces (README.md "Sphere fast path": force loop, contact
 * arithmetic): the sphere-sphere and sphere-wall kernels, the force loop over the lists (rebuilt
 * when a sphere moved more than half the skin) in parts of consecutive spheres, one per thread,
 * the overlap limit, and the sums handed to the body states. */
#include <math.h>
#include <omp.h>
#include <string.h>
#include "spheropoly_spheres_impl.h"


/* The spring of the last step onto the tangent plane of normal n, magnitude kept: the series of
 * the scale 1/sqrt(1 - u), u = (xi.n)^2/|xi|^2, for u <= 1e-5 (truncation < 3e-21; as the pair's),
 * else the square root. */
static inline vec3 spring_onto(vec3 xi, vec3 n)
{
    double m0 = v3_norm2(xi);
    if (m0 == 0.0) return xi;
    double pn = v3_dot(xi, n), p2 = pn * pn;
    vec3 r = v3_axpy(-pn, n, xi);
    if (p2 <= 1e-5 * m0) {
        double u = p2 / m0;
        return v3_scale(r, 1.0 + u * (0.5 + u * (0.375 + u * 0.3125)));
    }
    double m1 = v3_norm2(r);
    return m1 > 0.0 ? v3_scale(r, sqrt(m0 / m1)) : r;
}

/* Sphere a of a pair: its state and radius (loaded once per run of a's entries). */
typedef struct {
    vec3 x, v, w;
    double r;
} sps_side;

static inline __attribute__((always_inline)) void contact_kernel(const sps_side *A, vec3 dx, double d2, vec3 vb, vec3 wb,
                                                                 double rb, const dem_pair_law *law,
                                                                 const dem_pair_consts *pc, unsigned char *touch, vec3 *xip,
                                                                 double h, double maxov, vec3 *f, vec3 *ta, vec3 *tb,
                                                                 int *bad);

/* The force between sphere a and sphere b (b's state, the pair's law and constants, its spring and
 * contact flag) at the current positions: 1 in contact with the force on b in *f and the torques on
 * a and b in *ta, *tb (a gets -f), 0 out of contact. Updates the spring and the contact flag;
 * *bad |= the overlap exceeds maxov x the smaller radius. */
static inline __attribute__((always_inline)) int pair_kernel(const sps_side *A, vec3 xb, vec3 vb, vec3 wb, double rb,
                                                             const dem_pair_law *law, const dem_pair_consts *pc,
                                                             unsigned char *touch, vec3 *xip, double h, double maxov,
                                                             vec3 *f, vec3 *ta, vec3 *tb, int *bad)
{
    double rs = A->r + rb;
    vec3 dx = v3_sub(xb, A->x);
    double d2 = v3_norm2(dx);
    if (d2 >= rs * rs) {
        *touch = 0;
        return 0;
    }
    contact_kernel(A, dx, d2, vb, wb, rb, law, pc, touch, xip, h, maxov, f, ta, tb, bad);
    return 1;
}

/* pair_kernel's force for a pair in contact (d2 = |dx|^2 < (ra + rb)^2, dx = xb - xa). */
static inline __attribute__((always_inline)) void contact_kernel(const sps_side *A, vec3 dx, double d2, vec3 vb, vec3 wb,
                                                                 double rb, const dem_pair_law *law,
                                                                 const dem_pair_consts *pc, unsigned char *touch, vec3 *xip,
                                                                 double h, double maxov, vec3 *f, vec3 *ta, vec3 *tb,
                                                                 int *bad)
{
    double ra = A->r, rs = ra + rb;
    double d = sqrt(d2);
    double delta = rs - d;
    /* the spring onto the new tangent plane, magnitude kept: xi - (xi.n) n scaled by |xi| / |r|
     * = 1/sqrt(1 - u), u = (xi.n)^2 / |xi|^2. One division gives 1/d = d/d^2 and 1/|xi|^2 (it
     * needs no d, so it runs beside the square root); for u <= 1e-5
     * (the normal turned by < 0.2 degrees since the last step) the scale is the series
     * 1 + u/2 + 3u^2/8 + 5u^3/16 (truncation < 3e-21): no square root on the way to the force */
    vec3 xi = *xip, n;
    double m0 = *touch ? v3_norm2(xi) : 0.0;
    if (!(d > 1e-12 * rs)) {
        n = v3(0.0, 0.0, 1.0);
        xi = m0 > 0.0 ? spring_onto(xi, n) : v3(0.0, 0.0, 0.0);
    } else if (m0 > 1e-200) {
        double r = 1.0 / (d2 * m0);
        n = v3_scale(dx, d * (r * m0));
        double pn = v3_dot(xi, n), u = pn * pn * (r * d2);
        vec3 rx = v3_axpy(-pn, n, xi);
        if (u <= 1e-5) {
            xi = v3_scale(rx, 1.0 + u * (0.5 + u * (0.375 + u * 0.3125)));
        } else {
            double m1 = v3_norm2(rx);
            xi = m1 > 0.0 ? v3_scale(rx, sqrt(m0 / m1)) : rx;
        }
    } else {
        n = v3_scale(dx, 1.0 / d);
        xi = m0 > 0.0 ? spring_onto(xi, n) : v3(0.0, 0.0, 0.0);
    }
    /* contact point in the middle of the overlap: cp = xa + la n = xb - lb n */
    double la = ra - 0.5 * delta, lb = rb - 0.5 * delta;
    /* v_b(cp) - v_a(cp) = vb - va - (lb wb + la wa) x n */
    vec3 vr = v3_sub(v3_sub(vb, A->v), v3_cross(v3_axpy(la, A->w, v3_scale(wb, lb)), n));
    double vn = v3_dot(vr, n);
    vec3 vt = v3_axpy(-vn, n, vr);
    double ks, cn;
    double fn = dem_normal_force_pc(law, pc, delta, -vn, 1.0, &ks, &cn);
    xi = v3_axpy(h, vt, xi);
    vec3 ft = dem_tangential_force(law, &xi, vt, fn, ks, cn);
    /* torques about the centres: (cp - xa) x (-f) = -la n x ft, (cp - xb) x f = -lb n x ft */
    vec3 c = v3_cross(n, ft);
    *touch = 1;
    *xip = xi;
    *bad |= delta > maxov * (ra < rb ? ra : rb);
    *f = v3_axpy(fn, n, ft);
    *ta = v3_scale(c, -la);
    *tb = v3_scale(c, -lb);
}

/* pair_kernel for listed pair p. */
static inline int pair_force(const lahar_dem_engine *e, sp_spheres *s, int p, double h, vec3 *f, vec3 *ta, vec3 *tb,
                             int *bad)
{
    sps_list *l = &s->pl;
    int a = l->a[p], b = l->b[p];
    sps_side A = {s->x[a], s->v[a], s->w[a], s->rad[a]};
    return pair_kernel(&A, s->x[b], s->v[b], s->w[b], s->rad[b], &e->laws[s->mat[a] * e->nmat + s->mat[b]], &l->pc[p],
                       &l->touch[p], &l->xi[p], h, e->max_overlap, f, ta, tb, bad);
}

/* Sphere a against wall w, the centre within the sum of the radii of the face's plane
 * (dpl: signed distance along the wall's normal): vertex-face when the centre projects inside the
 * face, else the pair goes to the general narrow phase (edges and corners of the face; fall = 1,
 * returns 0). An entry whose centre was deep inside the face at the list build (`deep`: farther
 * than the skin from every edge) stays inside until the next build (a centre moves less than
 * skin/2), so the polygon test is skipped. The normal is the face's unit normal, towards the
 * sphere. Force on the sphere. */
static int wall_force(const lahar_dem_engine *e, sp_spheres *s, int p, double dpl, double h)
{
    sps_list *l = &s->wl;
    int a = l->a[p], w = l->b[p], wb = s->wall_body[w];
    const sp_geo *gw = &e->geo[wb];
    const vec3 xa = s->x[a];
    double ra = s->rad[a], rs = ra + gw->radius;
    vec3 nn = s->wunit[w], c = v3_axpy(-v3_dot(v3_sub(xa, s->wp0[w]), nn), nn, xa);
    if (!l->deep[p]) {
        int b0 = e->fstart[gw->fs0], m = e->fstart[gw->fs0 + 1] - b0;
        if (!geom_point_polygon_inside(xa, e->fw + b0, m, e->nw[gw->f0], &c)) {
            l->touch[p] = 0;
            l->fall[p] = 1;
            return 0;
        }
    }
    double d = fabs(dpl);
    vec3 n = dpl >= 0.0 ? nn : v3_neg(nn); /* from the wall to the sphere */
    vec3 cp = v3_scale(v3_add(v3_axpy(gw->radius, n, c), v3_axpy(-ra, n, xa)), 0.5);
    vec3 xi = l->touch[p] ? spring_onto(l->xi[p], n) : v3(0.0, 0.0, 0.0);
    vec3 rpa = v3_sub(cp, xa);
    vec3 vr = v3_add(s->v[a], v3_cross(s->w[a], rpa)); /* the wall is fixed */
    double vn = v3_dot(vr, n);
    vec3 vt = v3_axpy(-vn, n, vr);
    const dem_pair_law *law = &e->laws[s->mat[a] * e->nmat + gw->material];
    double ks, cn, delta = rs - d;
    double fn = dem_normal_force_pc(law, &l->pc[p], delta, -vn, 1.0, &ks, &cn);
    xi = v3_axpy(h, vt, xi);
    vec3 ft = dem_tangential_force(law, &xi, vt, fn, ks, cn);
    vec3 f = v3_axpy(fn, n, ft);
    l->touch[p] = 1;
    l->xi[p] = xi;
    l->f[p] = f;
    l->ta[p] = v3_cross(rpa, f);
    l->tb[p] = v3_cross(v3_sub(cp, e->st[wb].x), v3_neg(f));
    l->delta[p] = delta;
    return 1;
}

static int overlap_fault(lahar_dem_engine *e, int a, int b, double delta, double rmin, vec3 cp, char *err, size_t errlen)
{
    snprintf(err, errlen,
             "spheropoly: overlap %.3g m between bodies %d '%s' and %d '%s' exceeds %g x the smaller sweep radius %.3g m "
             "at substep %ld (time step too large or bodies interpenetrating)",
             delta, a, e->names[a], b, e->names[b], e->max_overlap, rmin, e->step);
    e->fault = (lahar_dem_fault){.body = a, .other = b, .value = delta, .limit = e->max_overlap * rmin, .substep = e->step};
    snprintf(e->fault.what, sizeof e->fault.what, "overlap");
    v3_store(cp, e->fault.x);
    e->has_fault = 1;
    return -1;
}

/* Phase 1 of part t (threaded only): the entries of its spheres whose partner belongs to a later
 * part, forces kept in the entry for the two sums. */
static void forces_cross(const lahar_dem_engine *e, sp_spheres *s, int t, double h, int *cnt, int *bad)
{
    sps_list *l = &s->pl;
    int c = 0, bd = 0;
    for (int q = s->xstart[t]; q < s->xstart[t + 1]; q++) {
        int p = s->xpair[q];
        c += pair_force(e, s, p, h, &l->f[p], &l->ta[p], &l->tb[p], &bd);
    }
    *cnt += c;
    *bad |= bd;
}

/* Phase 2 of part t: the sums of its spheres [k0, k1), each in ascending partner order (the
 * entries of earlier parts first, as their partners are smaller), then its walls. The sums of a
 * are kept in registers over its run of entries. */
static void forces_own(const lahar_dem_engine *e, sp_spheres *s, int t, double h, int *cnt, int *bad, int *nfall)
{
    sps_list *l = &s->pl, *wl = &s->wl;
    const int k0 = s->part[t], k1 = s->part[t + 1];
    memset(s->sf + k0, 0, sizeof(vec3) * (size_t)(k1 - k0));
    memset(s->st + k0, 0, sizeof(vec3) * (size_t)(k1 - k0));
    memset(s->scnt + k0, 0, sizeof(int) * (size_t)(k1 - k0));
    for (int q = s->xinstart[t]; q < s->xinstart[t + 1]; q++) { /* by (b, a): each b's sum in ascending a */
        int p = s->xin[q];
        if (!l->touch[p]) continue;
        int b = l->b[p];
        s->sf[b] = v3_add(s->sf[b], l->f[p]);
        s->st[b] = v3_add(s->st[b], l->tb[p]);
        s->scnt[b]++;
    }
    int c = 0, bd = 0;
    /* locals: the stores into the sums cannot alias them */
    const vec3 *x = s->x, *v = s->v, *w = s->w;
    const double *rad = s->rad, maxov = e->max_overlap;
    const int *bl = l->b, *pstart = s->pstart, *mat = s->mat, nmat = e->nmat;
    const dem_pair_consts *pc = l->pc;
    unsigned char *touch = l->touch;
    vec3 *xi = l->xi, *sf = s->sf, *st = s->st;
    int *scnt = s->scnt;
    const int *al = l->a;
    int *ci = l->ci;
    /* blocks of spheres: first the entries in contact, without a branch (the contact test is
     * data-dependent: a mispredicted branch per pair), then their forces */
    for (int a0 = k0; a0 < k1; a0 += 64) {
        const int a1 = a0 + 64 < k1 ? a0 + 64 : k1, p0 = pstart[a0], p1 = pstart[a1];
        int nc = p0;
        for (int p = p0; p < p1; p++) {
            int a = al[p], b = bl[p];
            double rs = rad[a] + rad[b];
            int in = v3_norm2(v3_sub(x[b], x[a])) < rs * rs, cross = b >= k1;
            unsigned char tp = touch[p];
            touch[p] = cross ? tp : (unsigned char)(tp & in); /* cross: phase 1 set it */
            ci[nc] = p;
            nc += cross ? tp : in;
        }
        for (int q = p0; q < nc; q++) {
            int p = ci[q], a = al[p], b = bl[p];
            if (b >= k1) { /* computed in phase 1 */
                scnt[a]++;
                sf[a] = v3_sub(sf[a], l->f[p]);
                st[a] = v3_add(st[a], l->ta[p]);
                continue;
            }
            const sps_side A = {x[a], v[a], w[a], rad[a]};
            vec3 dx = v3_sub(x[b], A.x), f, ta, tb;
            contact_kernel(&A, dx, v3_norm2(dx), v[b], w[b], rad[b], e->laws + mat[a] * nmat + mat[b], &pc[p], &touch[p],
                           &xi[p], h, maxov, &f, &ta, &tb, &bd);
            c++;
            scnt[a]++;
            sf[a] = v3_sub(sf[a], f);
            st[a] = v3_add(st[a], ta);
            sf[b] = v3_add(sf[b], f);
            st[b] = v3_add(st[b], tb);
            scnt[b]++;
        }
    }
    /* walls: the entries within reach of the plane first (no branch), then their forces */
    int nf = 0, nw = s->wstart[k0];
    int *wci = wl->ci;
    double *wd = wl->delta; /* scratch: the signed distances to the plane, overwritten by the overlaps */
    for (int p = s->wstart[k0]; p < s->wstart[k1]; p++) {
        int a = wl->a[p], w = wl->b[p];
        double dpl = v3_dot(v3_sub(x[a], s->wp0[w]), s->wnrm[w]);
        int in = fabs(dpl) < rad[a] + s->wrad[w];
        wl->touch[p] = (unsigned char)(wl->touch[p] & in);
        wl->fall[p] = 0;
        wd[p] = dpl;
        wci[nw] = p;
        nw += in;
    }
    for (int q = s->wstart[k0]; q < nw; q++) {
        int p = wci[q];
        if (!wall_force(e, s, p, wd[p], h)) {
            nf++;
            continue;
        }
        int a = wl->a[p];
        double ra = s->rad[a], rb = e->geo[s->wall_body[wl->b[p]]].radius;
        c++;
        bd |= wl->delta[p] > e->max_overlap * (ra < rb ? ra : rb);
        s->sf[a] = v3_add(s->sf[a], wl->f[p]);
        s->st[a] = v3_add(s->st[a], wl->ta[p]);
        s->scnt[a]++;
    }
    *cnt += c;
    *bad |= bd;
    *nfall += nf;
}

int sps_forces(lahar_dem_engine *e, double h, char *err, size_t errlen)
{
    sp_spheres *s = e->sph;
    /* rebuild when a sphere moved more than skin/2 since the last build (the drift keeps the
     * largest squared displacement) */
    double lim2 = 0.25 * s->skin * s->skin;
    if (!s->built || s->worst > lim2) {
        /* hand the springs over (after a restart the history is already in ph/wh) */
        if (s->built && (sps_hist_take(&s->ph, &s->pl) || sps_hist_take(&s->wh, &s->wl))) goto oom;
        if (sps_build_lists(e)) goto oom;
        sps_hist_give(&s->ph, &s->pl);
        sps_hist_give(&s->wh, &s->wl);
        s->worst = 0.0;
    }
    sps_list *pl = &s->pl, *wl = &s->wl;
    int cnt = 0, bad = 0, nfall = 0;
    const int np = s->npart;
    if (np == 1) {
        forces_own(e, s, 0, h, &cnt, &bad, &nfall);
    } else {
#pragma omp parallel num_threads(np) reduction(+ : cnt, nfall) reduction(| : bad)
        {
            /* a team smaller than asked for takes several parts per thread */
            int id = omp_get_thread_num(), nt = omp_get_num_threads();
            for (int t = id; t < np; t += nt) forces_cross(e, s, t, h, &cnt, &bad);
#pragma omp barrier
            for (int t = id; t < np; t += nt) forces_own(e, s, t, h, &cnt, &bad, &nfall);
        }
    }
    /* the overlap limit: the first offender in list order is reported */
    for (int p = 0; bad && p < pl->n; p++) {
        if (!pl->touch[p]) continue;
        int a = pl->a[p], b = pl->b[p];
        double rmin = fmin(s->rad[a], s->rad[b]);
        double delta = s->rad[a] + s->rad[b] - sqrt(v3_norm2(v3_sub(s->x[b], s->x[a])));
        if (delta > e->max_overlap * rmin) {
            vec3 xa = s->x[a], xb = s->x[b];
            return overlap_fault(e, s->body[a], s->body[b], delta, rmin, v3_scale(v3_add(xa, xb), 0.5), err, errlen);
        }
    }
    for (int p = 0; bad && p < wl->n; p++) {
        if (!wl->touch[p]) continue;
        int a = wl->a[p], wb = s->wall_body[wl->b[p]];
        double rmin = fmin(s->rad[a], e->geo[wb].radius);
        if (wl->delta[p] > e->max_overlap * rmin)
            return overlap_fault(e, s->body[a], wb, wl->delta[p], rmin, s->x[a], err, errlen);
    }
    s->ncontact = cnt;
    s->nfall = nfall;
    e->contacts_evaluated += cnt;
    return 0;
oom:
    snprintf(err, errlen, "spheropoly: out of memory for the sphere neighbour list");
    return -1;
}

int sps_fallback_pairs(lahar_dem_engine *e, int (*add)(lahar_dem_engine *, int, int))
{
    sp_spheres *s = e->sph;
    if (s->nfall == 0) return 0;
    for (int p = 0; p < s->wl.n; p++)
        if (s->wl.fall[p] && add(e, s->body[s->wl.a[p]], s->wall_body[s->wl.b[p]])) return -1;
    return 0;
}

void sps_defer(lahar_dem_engine *e) { e->sph->deferred = 1; }

void sps_accumulate(lahar_dem_engine *e)
{
    sp_spheres *s = e->sph;
    s->deferred = 0;
#pragma omp parallel for schedule(static) num_threads(e->nthr) if (s->n >= SPS_PAR_MIN)
    for (int k = 0; k < s->n; k++) {
        sp_state *st = &e->st[s->body[k]];
        st->fc = s->sf[k];
        st->tc = s->st[k];
        e->ncontact_body[s->body[k]] = s->scnt[k];
    }
}

void sps_accumulate_walls(lahar_dem_engine *e)
{
    sp_spheres *s = e->sph;
    /* the walls feel the reaction, summed in list order */
    const sps_list *wl = &s->wl;
    for (int p = 0; p < wl->n; p++) {
        if (!wl->touch[p]) continue;
        int wb = s->wall_body[wl->b[p]];
        e->st[wb].fc = v3_sub(e->st[wb].fc, wl->f[p]);
        e->st[wb].tc = v3_add(e->st[wb].tc, wl->tb[p]);
        e->ncontact_body[wb]++;
    }
}
