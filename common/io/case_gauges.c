/* The case loader: probes: (pressure and level), trackers: and control_volumes:. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>

#include "case_reader.h"
#include "geometry.h"
#include "vec.h"

/* probes: [{name, kind, position, body, size, rate}, ...] (lahar_probe, common/scene/scene.h). A fluid
 * probe must lie in the box of the bodies and blocks and outside every body; a body probe within
 * sph.dx of the body's swept surface (it is projected onto it, and the outward normal stored). A
 * level gauge (kind: level) gives the horizontal position only, inside the box; gravity must act
 * along the last axis (down); its floor is found below (case_level_floor). */
static void case_domain_box(const lahar_case *c, double lo[3], double hi[3])
{
    for (int a = 0; a < 3; a++)
        lo[a] = DBL_MAX, hi[a] = -DBL_MAX;
    for (int b = 0; b < c->nbody; b++) {
        const lahar_body *bd = &c->bodies[b];
        for (int v = 0; v < bd->shape.nv; v++) {
            vec3 w = geom_world_vertex(&bd->shape, bd->x, bd->q, v);
            double wa[3] = {w.x, w.y, w.z};
            for (int a = 0; a < c->dim; a++) {
                lo[a] = fmin(lo[a], wa[a] - bd->shape.radius);
                hi[a] = fmax(hi[a], wa[a] + bd->shape.radius);
            }
        }
    }
    for (int k = 0; k < c->nblock; k++)
        for (int a = 0; a < c->dim; a++) {
            lo[a] = fmin(lo[a], c->blocks[k].lo[a]);
            hi[a] = fmax(hi[a], c->blocks[k].hi[a]);
        }
    for (int a = c->dim; a < 3; a++)
        lo[a] = hi[a] = 0.0;
}

/* 1 if the world point q lies in any body's solid. */
static int case_in_solid(const lahar_case *c, const double q[3], int *hit)
{
    for (int b = 0; b < c->nbody; b++)
        if (lahar_body_contains(&c->bodies[b], c->dim, q)) {
            *hit = b;
            return 1;
        }
    return 0;
}

/* The floor under a level gauge at the horizontal position x (x[dim - 1] ignored): going up the
 * vertical (the last axis) from the bottom of the domain box lo..hi in steps of dx/16, the first
 * solid the line meets, and the point where the line leaves it (the union of the bodies; refined
 * by bisection to 1e-6 dx); lo when the line meets no solid. Returns the floor, or NAN when the
 * line stays inside body *hit up to hi. */
static double case_level_floor(const lahar_case *c, const double x[3], double lo, double hi, double dx, int *hit)
{
    const int v = c->dim - 1;
    double q[3] = {x[0], x[1], x[2]};
    const double step = dx / 16.0;
    *hit = -1;
    double z = lo + 0.5 * step, zin = lo;
    int met = 0;
    for (;; z += step) {
        if (z > hi)
            return met ? NAN : lo;
        q[v] = z;
        int in = case_in_solid(c, q, hit);
        if (in) {
            met = 1;
            zin = z;
        } else if (met) {
            break;
        }
    }
    double a = zin, b = z; /* a inside, b outside */
    int dummy;
    while (b - a > 1e-6 * dx) {
        q[v] = 0.5 * (a + b);
        if (case_in_solid(c, q, &dummy))
            a = q[v];
        else
            b = q[v];
    }
    *hit = -1;
    return b;
}

/* A level gauge (kind: level) of probes: at its horizontal position. */
static void read_level_gauge(reader *r, rmap *pm, const lahar_case *c, lahar_probe *pr, const double lo[3],
                             const double hi[3])
{
    const int dim = c->dim, v = dim - 1;
    const double dx = c->sph_dx;
    static const char *const axes[] = {"x", "y", "z"};
    if (rmap_get(pm, "body") || rmap_get(pm, "size")) {
        rmap_fail(pm, rmap_get(pm, "body") ? "body" : "size", "is a key of pressure sensors on a body; a level gauge "
                  "(kind: level) is a vertical line through the water: remove it");
        return;
    }
    int vertical = c->gravity[v] < 0.0;
    for (int a = 0; a < v; a++)
        vertical &= c->gravity[a] == 0.0;
    if (!vertical) {
        if (dim == 3)
            rmap_fail(pm, "kind", "level gauges measure along the vertical z and need gravity [0, 0, -g] (got [%g, %g, "
                      "%g]); use pressure probes in this case", c->gravity[0], c->gravity[1], c->gravity[2]);
        else
            rmap_fail(pm, "kind", "level gauges measure along the vertical y and need gravity [0, -g] (got [%g, %g]); "
                      "use pressure probes in this case", c->gravity[0], c->gravity[1]);
        return;
    }
    pr->body = -1;
    pr->size = 0.0;
    pr->rate = rd_key_num(pm, "rate");
    if (!rmap_vec(pm, "position", v, pr->x, 1, dim == 3 ? "[0.5, 0.3] (x, y of the vertical line)"
                                                           : "[0.5] (x of the vertical line)"))
        return;
    for (int a = 0; a < v; a++)
        if (!(pr->x[a] >= lo[a] && pr->x[a] <= hi[a])) {
            rmap_fail(pm, "position", "lies outside the domain (the box of the bodies and blocks, %s in [%g, %g]; got "
                      "%s = %g); a level gauge's position is the horizontal place of its vertical line",
                      axes[a], lo[a], hi[a], axes[a], pr->x[a]);
            return;
        }
    int hit;
    double fl = case_level_floor(c, pr->x, lo[v], hi[v], dx, &hit);
    if (isnan(fl)) {
        rmap_fail(pm, "position", "the vertical line there lies inside body '%s' up to the top of the domain (%s = "
                  "%g); move the gauge over the water", c->bodies[hit].name, axes[v], hi[v]);
        return;
    }
    pr->x[v] = fl;
    pr->top = hi[v] + dx;
    (void)r;
}

void case_read_probes(reader *r, yaml_node_t *n, lahar_case *c)
{
    if (!n || r->failed)
        return;
    if (n->type != YAML_SEQUENCE_NODE) {
        rd_fail(r, n, "probes", "expected a list of probes (lines starting with `- `), got %s", rd_node_kind(n));
        return;
    }
    if (c->nblock == 0) {
        rd_fail(r, n, "probes", "probes read the SPH fluid, but the case has no sph: blocks; remove probes "
                "or add an sph section");
        return;
    }
    int np = rd_seq_len(n);
    if (np == 0)
        return;
    c->probes = calloc((size_t)np, sizeof *c->probes);
    if (!c->probes) {
        rd_fail(r, n, "probes", "out of memory");
        return;
    }
    const int dim = r->dim;
    const double dx = c->sph_dx;
    double lo[3], hi[3];
    case_domain_box(c, lo, hi);
    for (int i = 0; i < np && !r->failed; i++) {
        lahar_probe *pr = &c->probes[i];
        c->nprobe = i + 1;
        char prefix[KEY_MAX], def[LAHAR_NAME_MAX];
        snprintf(prefix, sizeof prefix, "probes[%d]", i);
        snprintf(def, sizeof def, "probe%d", i);
        rmap pm;
        if (rmap_open(r, rd_seq_item(r, n, i), prefix, &pm) != 0)
            return;
        rmap_section(&pm, "probes[]");
        rmap_name(&pm, "name", 0, def, pr->name);
        for (int j = 0; j < i && !r->failed; j++)
            if (strcmp(c->probes[j].name, pr->name) == 0)
                rmap_fail(&pm, "name", "'%s' is already the name of probes[%d]; probe names must be unique", pr->name, j);
        pr->kind = rd_key_choice(&pm, "kind");
        if (r->failed)
            return;
        if (pr->kind == LAHAR_PROBE_LEVEL) {
            read_level_gauge(r, &pm, c, pr, lo, hi);
            if (r->failed)
                return;
            continue;
        }
        rmap_vec(&pm, "position", dim, pr->x, 1, dim == 3 ? "[0.5, 0.0, 0.01]" : "[0.5, 0.01]");
        pr->size = rd_key_num(&pm, "size");
        pr->rate = rd_key_num(&pm, "rate");
        pr->body = -1;
        const char *bname = rmap_str(&pm, "body", 0, NULL, "wall_right");
        if (r->failed)
            return;
        if (pr->size > 0.0 && !bname) {
            rmap_fail(&pm, "size", "is the diameter of a sensor on a body's surface; give body: NAME, or remove size "
                      "for a point probe in the fluid");
            return;
        }
        for (int a = 0; a < dim; a++)
            if (!(pr->x[a] >= lo[a] - dx && pr->x[a] <= hi[a] + dx)) {
                rmap_fail(&pm, "position", "lies outside the domain (the box of the bodies and blocks, %c in [%g, %g]; "
                          "got %c = %g)", "xyz"[a], lo[a], hi[a], "xyz"[a], pr->x[a]);
                return;
            }
        if (!bname) {
            for (int b = 0; b < c->nbody; b++)
                if (lahar_body_contains(&c->bodies[b], dim, pr->x)) {
                    rmap_fail(&pm, "position", "lies inside body '%s'; a probe without body: is a point in the fluid "
                              "(give body: %s for a sensor on its surface)", c->bodies[b].name, c->bodies[b].name);
                    return;
                }
            continue;
        }
        pr->body = lahar_case_find_body(c, bname);
        if (pr->body < 0) {
            rmap_fail(&pm, "body", "unknown body '%s'; give the name of one of the case's bodies", bname);
            return;
        }
        const lahar_body *bd = &c->bodies[pr->body];
        vec3 cp;
        int feat;
        double dcore = geom_point_body_core(&bd->shape, bd->x, bd->q, v3_load(pr->x), &cp, &feat);
        double R = bd->shape.radius, gap = dcore - R;
        int inside_core = dcore > R && lahar_body_contains(bd, dim, pr->x);
        if (inside_core || fabs(gap) > dx || !(dcore > 1e-9 * dx)) {
            if (inside_core)
                rmap_fail(&pm, "position", "must lie on the surface of body '%s' (within sph.dx = %g m of it), but it "
                          "is inside its core; move the point onto the surface", bname, dx);
            else
                rmap_fail(&pm, "position", "must lie on the surface of body '%s' (within sph.dx = %g m of it), but it "
                          "is %g m %s it; move the point onto the surface", bname, dx, fabs(gap), gap > 0 ? "off" : "inside");
            return;
        }
        vec3 nn = v3_scale(v3_sub(v3_load(pr->x), cp), 1.0 / dcore);
        vec3 xs = v3_axpy(R, nn, cp);
        pr->x[0] = xs.x, pr->x[1] = xs.y, pr->x[2] = dim == 3 ? xs.z : 0.0;
        pr->n[0] = nn.x, pr->n[1] = nn.y, pr->n[2] = dim == 3 ? nn.z : 0.0;
    }
}

/* trackers: [{name, position, rate}] and control_volumes: [{name, box: {lo, hi}, axis, rate}]:
 * probes of kinds LAHAR_PROBE_TRACKER / LAHAR_PROBE_CONTROL_VOLUME appended to c->probes
 * (sph_node/probes/sph_gauges.h). */
void case_read_gauges(reader *r, yaml_node_t *tn, yaml_node_t *vn, lahar_case *c)
{
    static const char *const boxkeys[] = {"lo", "hi", NULL};
    yaml_node_t *secs[2] = {tn, vn};
    const char *secname[2] = {"trackers", "control_volumes"};
    const int dim = r->dim;
    for (int sct = 0; sct < 2 && !r->failed; sct++) {
        yaml_node_t *n = secs[sct];
        if (!n)
            continue;
        if (n->type != YAML_SEQUENCE_NODE) {
            rd_fail(r, n, secname[sct], "expected a list (lines starting with `- `), got %s", rd_node_kind(n));
            return;
        }
        if (c->nblock == 0) {
            rd_fail(r, n, secname[sct], "%s read the SPH particles, but the case has no sph: blocks", secname[sct]);
            return;
        }
        int cnt = rd_seq_len(n);
        if (cnt == 0)
            continue;
        lahar_probe *np = realloc(c->probes, ((size_t)c->nprobe + cnt) * sizeof *np);
        if (!np) {
            rd_fail(r, n, secname[sct], "out of memory");
            return;
        }
        c->probes = np;
        for (int i = 0; i < cnt && !r->failed; i++) {
            lahar_probe *pr = &c->probes[c->nprobe];
            memset(pr, 0, sizeof *pr);
            c->nprobe++;
            char prefix[KEY_MAX], def[LAHAR_NAME_MAX];
            snprintf(prefix, sizeof prefix, "%s[%d]", secname[sct], i);
            snprintf(def, sizeof def, "%s%d", sct == 0 ? "tracker" : "cv", i);
            rmap pm;
            if (rmap_open(r, rd_seq_item(r, n, i), prefix, &pm) != 0)
                return;
            rmap_section(&pm, sct == 0 ? "trackers[]" : "control_volumes[]");
            rmap_name(&pm, "name", 0, def, pr->name);
            for (int j = 0; j < c->nprobe - 1 && !r->failed; j++)
                if (strcmp(c->probes[j].name, pr->name) == 0)
                    rmap_fail(&pm, "name", "'%s' is already the name of a probe, tracker or control volume; names "
                              "must be unique", pr->name);
            pr->body = -1;
            pr->rate = rd_key_num(&pm, "rate");
            if (sct == 0) {
                pr->kind = LAHAR_PROBE_TRACKER;
                rmap_vec(&pm, "position", dim, pr->x, 1, dim == 3 ? "[10.0, 0.0, 5.0]" : "[10.0, 5.0]");
                continue;
            }
            pr->kind = LAHAR_PROBE_CONTROL_VOLUME;
            pr->axis = rd_key_choice(&pm, "axis");
            if (!r->failed && pr->axis >= dim) {
                rmap_fail(&pm, "axis", "'z' is not an axis of a 2D case; use x or y");
                return;
            }
            yaml_node_t *bx = rmap_get(&pm, "box");
            if (!bx) {
                rmap_missing(&pm, "box", dim == 3 ? "{lo: [193.1, -10, 0], hi: [193.6, 10, 50]}"
                                                  : "{lo: [193.1, 0], hi: [193.6, 50]}");
                return;
            }
            char bk[KEY_MAX];
            rd_key_join(prefix, "box", bk);
            rmap xm;
            if (rmap_open(r, bx, bk, &xm) != 0)
                return;
            rmap_check_keys(&xm, boxkeys);
            rmap_vec(&xm, "lo", dim, pr->x, 1, dim == 3 ? "[0, 0, 0]" : "[0, 0]");
            rmap_vec(&xm, "hi", dim, pr->hi, 1, dim == 3 ? "[0.5, 1, 1]" : "[0.5, 1]");
            for (int k = 0; k < dim && !r->failed; k++)
                if (!(pr->hi[k] > pr->x[k]))
                    rmap_fail(&xm, "hi", "must be > lo in every component (component %d: %g <= %g)", k, pr->hi[k],
                              pr->x[k]);
        }
    }
}
