/* The case loader: the open boundaries inlets:, outlets: and domain: (common/scene/inflow.h). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>

#include "case_reader.h"

/* --- open boundaries: inlets:, outlets:, domain: (common/inflow.h) ---------------------------- */

/* position, edge(s) and unit normal of an inlet/outlet section; 0 or -1 */
static int read_section(rmap *m, int dim, double x0[3], double e1[3], double e2[3], double n[3], const char *nwhat)
{
    rmap_vec(m, "position", dim, x0, 1, dim == 3 ? "[0.0, 0.0, 0.0]" : "[0.0, 0.0]");
    rmap_vec(m, "edge", dim, e1, 1, dim == 3 ? "[0.0, 1.0, 0.0]" : "[0.0, 0.5]");
    if (dim == 3)
        rmap_vec(m, "edge2", 3, e2, 1, "[0.0, 0.0, 0.5]");
    else if (rmap_get(m, "edge2"))
        rmap_fail(m, "edge2", "is the second edge of a 3D rectangle; a 2D section is the line position + edge");
    rmap_vec(m, "normal", dim, n, 1, dim == 3 ? "[1.0, 0.0, 0.0]" : "[1.0, 0.0]");
    if (m->r->failed)
        return -1;
    const double l1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    const double l2 = sqrt(e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]);
    const double ln = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(l1 > 0.0) || (dim == 3 && !(l2 > 0.0))) {
        rmap_fail(m, !(l1 > 0.0) ? "edge" : "edge2", "must not be zero: the section is position + a edge%s, a in [0, 1]",
                  dim == 3 ? " + b edge2" : "");
        return -1;
    }
    if (!(ln > 0.0)) {
        rmap_fail(m, "normal", "must not be zero: the %s unit normal of the section", nwhat);
        return -1;
    }
    for (int a = 0; a < 3; a++)
        n[a] /= ln;
    const double d1 = (n[0] * e1[0] + n[1] * e1[1] + n[2] * e1[2]) / l1;
    const double d2 = dim == 3 ? (n[0] * e2[0] + n[1] * e2[1] + n[2] * e2[2]) / l2 : 0.0;
    const double d12 = dim == 3 ? (e1[0] * e2[0] + e1[1] * e2[1] + e1[2] * e2[2]) / (l1 * l2) : 0.0;
    if (fabs(d1) > 1e-6 || fabs(d2) > 1e-6) {
        rmap_fail(m, "normal", "must be perpendicular to the section's edge%s (cosine %g); give the %s normal of the "
                  "section", dim == 3 ? "s" : "", fmax(fabs(d1), fabs(d2)), nwhat);
        return -1;
    }
    if (fabs(d12) > 1e-6) {
        rmap_fail(m, "edge2", "must be perpendicular to edge (cosine %g): the section is a rectangle", d12);
        return -1;
    }
    return 0;
}

/* the solver features the open boundaries do not handle yet; 0 or -1 (message at n) */
static int open_boundary_support(reader *r, yaml_node_t *n, const char *key, const lahar_case *c)
{
    /* soil blocks are allowed: a removal carries the stress arrays (sph_particles_remove) and the
     * soil-DEM friction springs are kept by unique particle id (sph_coupling_enable_soil) */
    const char *why = NULL;
    if (c->sph.shifting > 0.0)
        why = "sph.shifting (it would move the buffer particles)";
    if (!why && c->sph.transport_velocity)
        why = "sph.transport_velocity (fully periodic flows only)";
    if (why) {
        rd_fail(r, n, key, "open boundaries (inlets, outlets, domain) do not work with %s; remove one or the other", why);
        return -1;
    }
    return 0;
}

/* the path of a CSV key, relative to the case file's directory; 0 or -1 */
static int inflow_csv(rmap *m, const char *key, char *full, size_t n)
{
    const char *file = rmap_str(m, key, 1, NULL, "inflow.csv");
    if (m->r->failed)
        return -1;
    if (file[0] == '/')
        snprintf(full, n, "%s", file);
    else
        snprintf(full, n, "%s%s", m->r->dir, file);
    return 0;
}

/* inlets[i].level (constant) or level_hydrograph (a t,h table: the level is its largest value, the
 * slots of the section). */
static int read_inlet_level(rmap *m, lahar_inlet *in)
{
    const int has_lt = rmap_get(m, "level_hydrograph") != NULL;
    if (has_lt && rmap_get(m, "level")) {
        rmap_fail(m, "level_hydrograph", "give either level: H (constant) or level_hydrograph: FILE.csv (t,h), "
                  "not both");
        return -1;
    }
    in->level = has_lt ? 1.0 : rd_key_num_req(m, "level", 1, NAN);
    if (!has_lt)
        return 0;
    char full[2048], err[1400];
    if (inflow_csv(m, "level_hydrograph", full, sizeof full) != 0)
        return -1;
    int kind = 0;
    in->nlevel = lahar_hydrograph_read_csv(full, &kind, &in->level_t, &in->level_h, err, (int)sizeof err);
    if (in->nlevel < 0) {
        in->nlevel = 0;
        rmap_fail(m, "level_hydrograph", "%s (paths are relative to the case file's directory)", err);
        return -1;
    }
    if (kind != LAHAR_HYDRO_TABLE_H) {
        rmap_fail(m, "level_hydrograph", "%s: the header must be `t,h` (a level table)", full);
        return -1;
    }
    in->level = 0.0;
    for (int k = 0; k < in->nlevel; k++) {
        if (!(in->level_h[k] >= 0.0)) {
            rmap_fail(m, "level_hydrograph", "%s: row %d (t = %g s) has a negative level %g m", full, k + 1,
                      in->level_t[k], in->level_h[k]);
            return -1;
        }
        in->level = fmax(in->level, in->level_h[k]);
    }
    return 0;
}

/* When the inlet runs, and its buffer's size: defaults and ranges from the key table (inlets[]);
 * 0 layers / max_particles: computed at set-up. */
static int read_inlet_window(rmap *m, lahar_inlet *in)
{
    in->t_start = rd_key_num(m, "start");
    in->t_end = rd_key_num_def(m, "end", 1e300);
    const double layers = rd_key_num_def(m, "layers", 0.0);
    const double maxp = rd_key_num_def(m, "max_particles", 0.0);
    if (m->r->failed)
        return -1;
    if (!(in->level > 0.0)) {
        rmap_fail(m, in->nlevel ? "level_hydrograph" : "level", "must be > 0 (got %g%s): the water depth above the "
                  "section's lowest point, m", in->level, in->nlevel ? " at most" : "");
        return -1;
    }
    if (!(in->t_end > in->t_start)) {
        rmap_fail(m, "end", "must be after start (%g s; got %g s): the inflow runs in [start, end)", in->t_start,
                  in->t_end);
        return -1;
    }
    in->layers = (int)layers;
    in->max_particles = (int64_t)maxp;
    return 0;
}

/* hydrograph: FILE.csv, a t,u or t,Q table of non-negative values. */
static int read_inlet_hydrograph(rmap *m, lahar_inlet *in)
{
    char full[2048], err[1400];
    if (inflow_csv(m, "hydrograph", full, sizeof full) != 0)
        return -1;
    in->ntable = lahar_hydrograph_read_csv(full, &in->kind, &in->table_t, &in->table_v, err, (int)sizeof err);
    if (in->ntable < 0) {
        in->ntable = 0;
        rmap_fail(m, "hydrograph", "%s (paths are relative to the case file's directory)", err);
        return -1;
    }
    if (in->kind == LAHAR_HYDRO_TABLE_H) {
        rmap_fail(m, "hydrograph", "%s holds a level (header t,h); give it as level_hydrograph:, and the inflow as "
                  "t,u or t,Q", full);
        return -1;
    }
    for (int k = 0; k < in->ntable; k++)
        if (!(in->table_v[k] >= 0.0)) {
            rmap_fail(m, "hydrograph", "%s: row %d (t = %g s) has a negative value %g; the inflow is along the "
                      "inward normal (no backflow through an inlet)", full, k + 1, in->table_t[k], in->table_v[k]);
            return -1;
        }
    return 0;
}

/* The inflow: exactly one of velocity, gumbel or hydrograph. The buffer only moves forward (rows
 * are created behind it): no backflow through an inlet. */
static int read_inlet_flow(rmap *m, const char *prefix, lahar_inlet *in)
{
    reader *r = m->r;
    const int has_v = rmap_get(m, "velocity") != NULL, has_g = rmap_get(m, "gumbel") != NULL,
              has_h = rmap_get(m, "hydrograph") != NULL;
    if (has_v + has_g + has_h != 1) {
        rd_fail(r, m->node, prefix, "give exactly one of velocity: U (m/s), gumbel: [a_G, beta_G, mu_G] "
                "(Trujillo-Vela et al. 2020, eq. 36) or hydrograph: FILE.csv (header t,u or t,Q)%s",
                has_v + has_g + has_h ? "; it has more than one" : "");
        return -1;
    }
    if (has_h)
        return read_inlet_hydrograph(m, in);
    if (has_v) {
        in->kind = LAHAR_HYDRO_CONSTANT;
        in->velocity = rd_key_num_req(m, "velocity", 1, NAN);
        return 0;
    }
    in->kind = LAHAR_HYDRO_GUMBEL;
    rmap_vec(m, "gumbel", 3, in->gumbel, 1, "[35, 2, 3]");
    if (!r->failed && !(in->gumbel[1] > 0.0)) {
        rmap_fail(m, "gumbel", "beta_G (the second number) must be > 0 (got %g s)", in->gumbel[1]);
        return -1;
    }
    if (!r->failed && !(in->gumbel[0] >= 0.0)) {
        rmap_fail(m, "gumbel", "a_G (the first number) must be >= 0 (got %g m): the inflow is along the inward "
                  "normal", in->gumbel[0]);
        return -1;
    }
    return 0;
}

static int read_inlet(reader *r, yaml_node_t *item, int i, lahar_inlet *in)
{
    char prefix[KEY_MAX], def[LAHAR_NAME_MAX];
    snprintf(prefix, sizeof prefix, "inlets[%d]", i);
    snprintf(def, sizeof def, "inlet%d", i);
    rmap m;
    if (rmap_open(r, item, prefix, &m) != 0)
        return -1;
    rmap_section(&m, "inlets[]");
    rmap_name(&m, "name", 0, def, in->name);
    if (read_section(&m, r->dim, in->x0, in->e1, in->e2, in->n, "inward") != 0 || read_inlet_level(&m, in) != 0 ||
        read_inlet_window(&m, in) != 0)
        return -1;
    return read_inlet_flow(&m, prefix, in);
}

void case_read_inlets(reader *r, yaml_node_t *n, lahar_case *c)
{
    if (!n || r->failed)
        return;
    if (n->type != YAML_SEQUENCE_NODE) {
        rd_fail(r, n, "inlets", "expected a list of inlets (lines starting with `- `), got %s", rd_node_kind(n));
        return;
    }
    if (c->nblock == 0) {
        rd_fail(r, n, "inlets", "inlets feed the SPH fluid, but the case has no sph: blocks; add an sph section with "
                "at least one block");
        return;
    }
    if (open_boundary_support(r, n, "inlets", c) != 0)
        return;
    const int ni = rd_seq_len(n);
    if (ni == 0)
        return;
    if (!(c->inlets = calloc((size_t)ni, sizeof *c->inlets))) {
        rd_fail(r, n, "inlets", "out of memory");
        return;
    }
    for (int i = 0; i < ni && !r->failed; i++) {
        c->ninlet = i + 1;
        if (read_inlet(r, rd_seq_item(r, n, i), i, &c->inlets[i]) != 0)
            return;
    }
}

void case_read_outlets(reader *r, yaml_node_t *n, lahar_case *c)
{
    if (!n || r->failed)
        return;
    if (n->type != YAML_SEQUENCE_NODE) {
        rd_fail(r, n, "outlets", "expected a list of outlets (lines starting with `- `), got %s", rd_node_kind(n));
        return;
    }
    if (c->nblock == 0) {
        rd_fail(r, n, "outlets", "outlets remove SPH particles, but the case has no sph: blocks");
        return;
    }
    if (open_boundary_support(r, n, "outlets", c) != 0)
        return;
    const int no = rd_seq_len(n);
    if (no == 0)
        return;
    if (!(c->outlets = calloc((size_t)no, sizeof *c->outlets))) {
        rd_fail(r, n, "outlets", "out of memory");
        return;
    }
    for (int i = 0; i < no && !r->failed; i++) {
        lahar_outlet *o = &c->outlets[i];
        c->noutlet = i + 1;
        char prefix[KEY_MAX], def[LAHAR_NAME_MAX];
        snprintf(prefix, sizeof prefix, "outlets[%d]", i);
        snprintf(def, sizeof def, "outlet%d", i);
        rmap m;
        if (rmap_open(r, rd_seq_item(r, n, i), prefix, &m) != 0)
            return;
        rmap_section(&m, "outlets[]");
        rmap_name(&m, "name", 0, def, o->name);
        if (read_section(&m, r->dim, o->x0, o->e1, o->e2, o->n, "outward") != 0)
            return;
        o->depth = rd_key_num_def(&m, "depth", 1e30);
    }
}

/* The particles of every block and inlet start inside the domain box: what starts outside would be
 * removed at the first step (a run that "finishes" with no fluid). Blocks by their box (a
 * polygon's or mesh's bounding box: its extreme points are the region's), inlets by the corners
 * of their section. */
static void check_inside_domain(rmap *m, const lahar_case *c)
{
    const int dim = c->dim;
    const double tol = 1e-9 * (c->sph_dx > 0.0 ? c->sph_dx : 1.0);
    for (int b = 0; b < c->nblock; b++) {
        const lahar_particle_block *pb = &c->blocks[b];
        for (int a = 0; a < dim; a++)
            if (pb->lo[a] < c->domain_lo[a] - tol || pb->hi[a] > c->domain_hi[a] + tol) {
                rd_fail(m->r, m->node, "domain", "sph.blocks[%d] '%s' reaches outside the domain box (%c: block [%g, "
                        "%g], domain [%g, %g]); its particles there would be removed at the first step: enlarge the "
                        "domain or move the block", b, pb->name, "xyz"[a], pb->lo[a], pb->hi[a], c->domain_lo[a],
                        c->domain_hi[a]);
                return;
            }
    }
    for (int i = 0; i < c->ninlet; i++) {
        const lahar_inlet *in = &c->inlets[i];
        for (int k = 0; k < (dim == 3 ? 4 : 2); k++) {
            double p[3];
            for (int a = 0; a < 3; a++)
                p[a] = in->x0[a] + ((k & 1) ? in->e1[a] : 0.0) + ((k & 2) ? in->e2[a] : 0.0);
            for (int a = 0; a < dim; a++)
                if (p[a] < c->domain_lo[a] - tol || p[a] > c->domain_hi[a] + tol) {
                    rd_fail(m->r, m->node, "domain", "inlets[%d] '%s' has its section outside the domain box (%c = %g "
                            "at a corner, domain [%g, %g]); the particles it creates would be removed at once: enlarge "
                            "the domain or move the inlet", i, in->name, "xyz"[a], p[a], c->domain_lo[a],
                            c->domain_hi[a]);
                    return;
                }
        }
    }
}

void case_read_domain(reader *r, yaml_node_t *n, lahar_case *c)
{
    if (!n || r->failed)
        return;
    rmap m;
    if (rmap_open(r, n, "domain", &m) != 0)
        return;
    if (c->nblock == 0) {
        rd_fail(r, n, "domain", "the domain box removes SPH particles, but the case has no sph: blocks");
        return;
    }
    if (open_boundary_support(r, n, "domain", c) != 0)
        return;
    rmap_section(&m, "domain");
    const int dim = r->dim;
    rmap_vec(&m, "lo", dim, c->domain_lo, 1, dim == 3 ? "[-1, -1, -1]" : "[-1, -1]");
    rmap_vec(&m, "hi", dim, c->domain_hi, 1, dim == 3 ? "[1, 1, 1]" : "[1, 1]");
    if (r->failed)
        return;
    for (int a = 0; a < dim; a++)
        if (!(c->domain_hi[a] > c->domain_lo[a])) {
            rmap_fail(&m, "hi", "must exceed lo on every axis (%c: lo %g, hi %g)", "xyz"[a], c->domain_lo[a],
                      c->domain_hi[a]);
            return;
        }
    check_inside_domain(&m, c);
    c->has_domain = 1;
}
