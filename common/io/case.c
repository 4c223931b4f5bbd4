/* Case file loader (see case.h; every key is documented in cases/dem_drop_3d.yaml).
 *
 * libyaml builds the document (yaml_parser_load: aliases resolve to shared nodes, every node
 * carries its line); a small typed-accessor layer below reads numbers, vectors, strings and
 * enums with defaults and reports the first problem as `file:line: key.path: what; what to do`. */
#include "case.h"

#include <errno.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <hdf5.h>
#include <matheval.h>
#include <yaml.h>

#include "case_keys.h"
#include "geometry.h"
#include "kernel.h"
#include "terrain.h"
#include "vec.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define KEY_MAX 192

/* --- reader: the document, the first error, and the typed accessors ------------------------- */

typedef struct {
    const char *path;
    char dir[1024]; /* directory of the case file: relative STL paths start here */
    yaml_document_t *doc;
    int failed;
    char *err;
    size_t errlen;
    int dim;
    /* the terrain: section (terrain.h), kept for sph.blocks[i].between */
    yaml_node_t *terrain_node;
    double (*terrain_pts)[3]; /* 2D: its polyline */
    int terrain_npts;
    lahar_heightmap terrain_hm; /* 3D: its grid (z NULL without one) */
    double terrain_radius;      /* its sweep radius */
    double dx;                  /* sph.dx once read (for sph.blocks[i].between) */
} reader;

static void rd_fail(reader *r, const yaml_node_t *n, const char *key, const char *fmt, ...)
{
    if (r->failed)
        return;
    r->failed = 1;
    int line = n ? (int)n->start_mark.line + 1 : 1;
    int k = snprintf(r->err, r->errlen, "%s:%d: %s%s", r->path, line, key ? key : "", key && *key ? ": " : "");
    if (k < 0 || (size_t)k >= r->errlen)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->err + k, r->errlen - (size_t)k, fmt, ap);
    va_end(ap);
}

static yaml_node_t *rd_node(reader *r, int id) { return yaml_document_get_node(r->doc, id); }

static const char *node_kind(const yaml_node_t *n)
{
    switch (n->type) {
    case YAML_SCALAR_NODE: return "a scalar";
    case YAML_SEQUENCE_NODE: return "a list";
    case YAML_MAPPING_NODE: return "a mapping";
    default: return "nothing";
    }
}

static const char *scalar(const yaml_node_t *n) { return (const char *)n->data.scalar.value; }

static int seq_len(const yaml_node_t *n)
{
    return (int)(n->data.sequence.items.top - n->data.sequence.items.start);
}

static yaml_node_t *seq_item(reader *r, const yaml_node_t *n, int i)
{
    return rd_node(r, n->data.sequence.items.start[i]);
}

/* Edit distance for "did you mean" (keys are short). */
static int edit_distance(const char *a, const char *b)
{
    int la = (int)strlen(a), lb = (int)strlen(b);
    if (la > 63 || lb > 63)
        return 99;
    int d[64][64];
    for (int i = 0; i <= la; i++)
        d[i][0] = i;
    for (int j = 0; j <= lb; j++)
        d[0][j] = j;
    for (int i = 1; i <= la; i++)
        for (int j = 1; j <= lb; j++) {
            int c = d[i - 1][j - 1] + (a[i - 1] != b[j - 1]);
            if (d[i - 1][j] + 1 < c)
                c = d[i - 1][j] + 1;
            if (d[i][j - 1] + 1 < c)
                c = d[i][j - 1] + 1;
            d[i][j] = c;
        }
    return d[la][lb];
}

/* Closest of names[] (NULL-terminated) to s, or NULL when nothing is close. */
static const char *closest_name(const char *s, const char *const *names)
{
    const char *best = NULL;
    int bd = 1 << 30;
    for (int i = 0; names[i]; i++) {
        int d = edit_distance(s, names[i]);
        if (d < bd) {
            bd = d;
            best = names[i];
        }
    }
    int len = (int)strlen(s);
    return bd <= (len > 6 ? 3 : 2) ? best : NULL;
}

static void join_names(const char *const *names, char *out, size_t n)
{
    size_t k = 0;
    out[0] = '\0';
    for (int i = 0; names[i] && k < n; i++) {
        int w = snprintf(out + k, n - k, "%s%s", i ? ", " : "", names[i]);
        if (w < 0)
            break;
        k += (size_t)w;
    }
}

/* A mapping being read: its node and the key path prefix for messages ("bodies[3]"). */
typedef struct {
    reader *r;
    yaml_node_t *node;
    char prefix[KEY_MAX];
    const lahar_key_section *sec; /* the section's key table (case_keys.c), once rmap_section ran */
} rmap;

static void key_join(const char *prefix, const char *key, char out[KEY_MAX])
{
    if (prefix[0])
        snprintf(out, KEY_MAX, "%.*s.%s", KEY_MAX / 2, prefix, key);
    else
        snprintf(out, KEY_MAX, "%s", key);
}

static int rmap_open(reader *r, yaml_node_t *n, const char *prefix, rmap *m)
{
    m->r = r;
    m->node = n;
    m->sec = NULL;
    snprintf(m->prefix, sizeof m->prefix, "%s", prefix);
    if (r->failed)
        return -1;
    if (!n || n->type != YAML_MAPPING_NODE) {
        rd_fail(r, n, prefix, "expected a mapping of keys to values, got %s; write it as {key: value, ...} "
                "or as indented key: value lines", n ? node_kind(n) : "nothing");
        return -1;
    }
    return 0;
}

static yaml_node_t *rmap_get(const rmap *m, const char *key)
{
    if (m->r->failed || !m->node)
        return NULL;
    for (yaml_node_pair_t *p = m->node->data.mapping.pairs.start; p < m->node->data.mapping.pairs.top; p++) {
        yaml_node_t *k = rd_node(m->r, p->key);
        if (k && k->type == YAML_SCALAR_NODE && strcmp(scalar(k), key) == 0)
            return rd_node(m->r, p->value);
    }
    return NULL;
}

/* Report the first key that is not in known[] (with a suggestion) or appears twice. */
static void rmap_check_keys(rmap *m, const char *const *known)
{
    reader *r = m->r;
    if (r->failed)
        return;
    for (yaml_node_pair_t *p = m->node->data.mapping.pairs.start; p < m->node->data.mapping.pairs.top; p++) {
        yaml_node_t *k = rd_node(r, p->key);
        char key[KEY_MAX];
        if (!k || k->type != YAML_SCALAR_NODE) {
            rd_fail(r, k, m->prefix, "a key must be a plain name, got %s", k ? node_kind(k) : "nothing");
            return;
        }
        key_join(m->prefix, scalar(k), key);
        int ok = 0;
        for (int i = 0; known[i] && !ok; i++)
            ok = strcmp(known[i], scalar(k)) == 0;
        if (!ok) {
            char list[512];
            join_names(known, list, sizeof list);
            const char *near = closest_name(scalar(k), known);
            if (near)
                rd_fail(r, k, key, "unknown key; did you mean '%s'? (known keys here: %s)", near, list);
            else
                rd_fail(r, k, key, "unknown key; known keys here: %s", list);
            return;
        }
        for (yaml_node_pair_t *q = m->node->data.mapping.pairs.start; q < p; q++) {
            yaml_node_t *k2 = rd_node(r, q->key);
            if (k2 && k2->type == YAML_SCALAR_NODE && strcmp(scalar(k2), scalar(k)) == 0) {
                rd_fail(r, k, key, "duplicate key (first given on line %d); keep only one",
                        (int)k2->start_mark.line + 1);
                return;
            }
        }
    }
}

static void rmap_missing(rmap *m, const char *key, const char *example)
{
    char full[KEY_MAX];
    key_join(m->prefix, key, full);
    rd_fail(m->r, m->node, full, "missing required key; add e.g. `%s: %s`", key, example);
}

/* Fail on the value of `key` (or on the mapping when the key is absent). */
static void rmap_fail(rmap *m, const char *key, const char *fmt, ...)
{
    if (m->r->failed)
        return;
    char full[KEY_MAX], msg[512];
    key_join(m->prefix, key, full);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    yaml_node_t *n = rmap_get(m, key);
    rd_fail(m->r, n ? n : m->node, full, "%s", msg);
}

static int node_number(reader *r, yaml_node_t *n, const char *key, double *out)
{
    if (r->failed)
        return -1;
    if (n->type != YAML_SCALAR_NODE) {
        rd_fail(r, n, key, "expected a number, got %s; write a plain number such as 0.05 or 1e-3", node_kind(n));
        return -1;
    }
    const char *s = scalar(n);
    char *end = NULL;
    errno = 0;
    double v = strtod(s, &end);
    while (end && (*end == ' ' || *end == '\t'))
        end++;
    if (end == s || !end || *end != '\0' || errno == ERANGE || !isfinite(v)) {
        rd_fail(r, n, key, "expected a finite number, got '%s'; write a plain number such as 0.05 or 1e-3", s);
        return -1;
    }
    *out = v;
    return 0;
}

static double rmap_num(rmap *m, const char *key, int required, double def, const char *example)
{
    yaml_node_t *n = rmap_get(m, key);
    if (!n) {
        if (required && !m->r->failed)
            rmap_missing(m, key, example);
        return def;
    }
    char full[KEY_MAX];
    key_join(m->prefix, key, full);
    double v = def;
    node_number(m->r, n, full, &v);
    return v;
}

/* A list of exactly n numbers into out (left untouched when absent). Returns 1 if present. */
static int node_vec(reader *r, yaml_node_t *n, const char *key, int count, double *out)
{
    if (r->failed)
        return 0;
    if (n->type != YAML_SEQUENCE_NODE || seq_len(n) != count) {
        if (n->type == YAML_SEQUENCE_NODE)
            rd_fail(r, n, key, "expected a list of %d numbers, got %d%s", count, seq_len(n),
                    count == 2 ? " (2D cases give [x, y])" : (count == 3 ? " (3D cases give [x, y, z])" : ""));
        else
            rd_fail(r, n, key, "expected a list of %d numbers like [%s], got %s", count,
                    count == 2 ? "x, y" : (count == 3 ? "x, y, z" : "a, b, ..."), node_kind(n));
        return 0;
    }
    double tmp[16];
    for (int i = 0; i < count && i < 16; i++) {
        char ik[KEY_MAX];
        snprintf(ik, sizeof ik, "%.*s[%d]", KEY_MAX - 16, key, i);
        if (node_number(r, seq_item(r, n, i), ik, &tmp[i]) != 0)
            return 0;
    }
    memcpy(out, tmp, (size_t)count * sizeof *out);
    return 1;
}

static int rmap_vec(rmap *m, const char *key, int count, double *out, int required, const char *example)
{
    yaml_node_t *n = rmap_get(m, key);
    if (!n) {
        if (required && !m->r->failed)
            rmap_missing(m, key, example);
        return 0;
    }
    char full[KEY_MAX];
    key_join(m->prefix, key, full);
    return node_vec(m->r, n, full, count, out);
}

static const char *rmap_str(rmap *m, const char *key, int required, const char *def, const char *example)
{
    yaml_node_t *n = rmap_get(m, key);
    if (!n) {
        if (required && !m->r->failed)
            rmap_missing(m, key, example);
        return def;
    }
    if (n->type != YAML_SCALAR_NODE || scalar(n)[0] == '\0') {
        rmap_fail(m, key, "expected a non-empty name/text, got %s", n->type == YAML_SCALAR_NODE ? "an empty value" : node_kind(n));
        return def;
    }
    return scalar(n);
}

/* A name shorter than LAHAR_NAME_MAX. */
static void rmap_name(rmap *m, const char *key, int required, const char *def, char out[LAHAR_NAME_MAX])
{
    const char *s = rmap_str(m, key, required, def, "name");
    if (m->r->failed)
        return;
    if (strlen(s) >= LAHAR_NAME_MAX) {
        rmap_fail(m, key, "name '%.20s...' is longer than %d characters; shorten it", s, LAHAR_NAME_MAX - 1);
        return;
    }
    snprintf(out, LAHAR_NAME_MAX, "%s", s);
}

static int rmap_enum(rmap *m, const char *key, const char *const *names, int required, int def)
{
    const char *s = rmap_str(m, key, required, NULL, names[0]);
    if (!s || m->r->failed)
        return def;
    for (int i = 0; names[i]; i++)
        if (strcmp(s, names[i]) == 0)
            return i;
    char list[256];
    join_names(names, list, sizeof list);
    const char *near = closest_name(s, names);
    if (near)
        rmap_fail(m, key, "unknown value '%s'; did you mean '%s'? (one of: %s)", s, near, list);
    else
        rmap_fail(m, key, "unknown value '%s'; use one of: %s", s, list);
    return def;
}

static int rmap_bool(rmap *m, const char *key, int def)
{
    static const char *const names[] = {"false", "true", "no", "yes", NULL};
    int v = rmap_enum(m, key, names, 0, def ? 1 : 0);
    return v == 1 || v == 3;
}

/* The keys of this mapping are those of `path`'s table (case_keys.c): report the first unknown or
 * repeated one; key_num and key_whole then take defaults and ranges from the table. */
static void rmap_section(rmap *m, const char *path)
{
    m->sec = lahar_key_section_find(path);
    const char *known[64];
    int n = 0;
    for (const lahar_key *k = m->sec ? m->sec->keys : NULL; k && k->name && n < 63; k++)
        known[n++] = k->name;
    known[n] = NULL;
    rmap_check_keys(m, known);
}

/* A number key of the section's table: required or its default `def` (the table's default when it
 * is a number and def is NaN), checked against the table's range with the table's message. */
static double key_num_def(rmap *m, const char *key, double def)
{
    const lahar_key *k = lahar_key_find(m->sec, key);
    if (!k) { /* a key missing from the table is a bug of the loader, not of the case */
        rmap_fail(m, key, "internal: no entry in the key table (common/io/case_keys.c)");
        return def;
    }
    if (isnan(def))
        def = lahar_key_default(k);
    char example[32];
    snprintf(example, sizeof example, "%s", k->def && !isnan(lahar_key_default(k)) ? k->def : "1");
    int present = rmap_get(m, key) != NULL;
    double v = rmap_num(m, key, k->required, def, example);
    if (m->r->failed || !present)
        return v;
    if (!lahar_key_in_range(k, v)) {
        char msg[512];
        lahar_key_range_error(k, v, msg, sizeof msg);
        rmap_fail(m, key, "%s", msg);
    }
    return v;
}

static double key_num(rmap *m, const char *key) { return key_num_def(m, key, NAN); }

/* --- case sections ------------------------------------------------------------------------------- */

static void read_time(reader *r, yaml_node_t *root, yaml_node_t *n, lahar_case *c)
{
    rmap m;
    if (!n) {
        rd_fail(r, root, "time",
                "missing required section; add e.g. `time: {end: 1.0, dt_max: 1e-3}`");
        return;
    }
    if (rmap_open(r, n, "time", &m) != 0)
        return;
    rmap_section(&m, "time");
    c->t_end = key_num(&m, "end");
    c->dt_max = key_num(&m, "dt_max");
    c->dt_min = key_num(&m, "dt_min");
    c->output_interval = key_num_def(&m, "output_interval", c->t_end / 100.0);
    c->forces_interval = key_num(&m, "forces_interval");
    if (r->failed)
        return;
    if (c->dt_min > c->dt_max)
        rmap_fail(&m, "dt_min", "must be <= dt_max = %g (got %g); it is the step below which a run stops",
                  c->dt_max, c->dt_min);
    else if (c->output_interval > c->t_end)
        rmap_fail(&m, "output_interval", "is larger than the end time (%g > %g s), so nothing after t = 0 would be "
                  "written; make it <= end", c->output_interval, c->t_end);
}

/* A model: soil material (an SPH soil, sph_node/soil/sph_soil.h): elastic constants, Mohr-Coulomb
 * strength (angles in degrees in the case, radians in lahar_material), k_h for seepage and mu_phi
 * against DEM surfaces (friction, default tan(friction_angle)). */
static void read_soil_material(rmap *m, lahar_material *mat, const char *const *dem_only)
{
    const double deg = acos(-1.0) / 180.0;
    for (int k = 0; dem_only[k] && !m->r->failed; k++)
        if (rmap_get(m, dem_only[k]))
            rmap_fail(m, dem_only[k], "is a DEM contact key, but this material is an SPH soil (model: soil); remove "
                      "it (the soil-DEM contact uses the SPH coupling's K_n, Trujillo-Vela et al. 2020 eq. 15)");
    mat->young = rmap_num(m, "young", 1, 0.0, "8.4e5");
    mat->poisson = rmap_num(m, "poisson", 0, 0.3, "0.3");
    double phi = rmap_num(m, "friction_angle", 1, 0.0, "30");
    double coh = rmap_num(m, "cohesion", 0, 0.0, "0");
    double psi = rmap_num(m, "dilatancy", 0, 0.0, "0");
    double kh = rmap_num(m, "permeability", 0, 0.0, "1e-3");
    double cd = rmap_num(m, "damping", 0, 0.0, "100");
    double ava = rmap_num(m, "av_alpha", 0, 0.1, "1.0"), avb = rmap_num(m, "av_beta", 0, 0.0, "1.0");
    if (m->r->failed)
        return;
    mat->friction = rmap_num(m, "friction", 0, tan(phi * deg), "0.5");
    if (m->r->failed)
        return;
    mat->friction_angle = phi * deg;
    mat->cohesion = coh;
    mat->dilatancy = psi * deg;
    mat->permeability = kh;
    mat->damping = cd;
    mat->av_alpha = ava;
    mat->av_beta = avb;
    mat->restitution = 1.0;
    mat->kt_ratio = 2.0 / 7.0;
    if (!(mat->density > 0))
        rmap_fail(m, "density", "must be > 0 kg/m^3 (got %g); the soil's bulk density, e.g. 2000", mat->density);
    else if (!(mat->young > 0))
        rmap_fail(m, "young", "must be > 0 Pa (got %g); the soil's Young's modulus, e.g. 8.4e5", mat->young);
    else if (!(mat->poisson >= 0 && mat->poisson < 0.5))
        rmap_fail(m, "poisson", "must be in [0, 0.5) (got %g)", mat->poisson);
    else if (!(phi >= 0 && phi < 90))
        rmap_fail(m, "friction_angle", "must be in [0, 90) degrees (got %g); sands are about 30", phi);
    else if (!(coh >= 0))
        rmap_fail(m, "cohesion", "must be >= 0 Pa (got %g); 0 for a dry sand", coh);
    else if (!(phi > 0 || coh > 0))
        rmap_fail(m, "cohesion", "a soil with friction_angle 0 needs cohesion > 0 (it would have no strength)");
    else if (!(psi >= 0 && psi <= phi))
        rmap_fail(m, "dilatancy", "must be in [0, friction_angle = %g] degrees (got %g); 0 is usual", phi, psi);
    else if (!(cd >= 0))
        rmap_fail(m, "damping", "must be >= 0 1/s (got %g); 0 = off, about the column's first frequency pi c/(2 H) "
                  "damps its start-up in a few periods", cd);
    else if (!(ava >= 0))
        rmap_fail(m, "av_alpha", "must be >= 0 (got %g); Monaghan's alpha of the soil, 0.1 by default, 1 in Trujillo-Vela et al.'s (2020) "
                  "granular impact", ava);
    else if (!(avb >= 0))
        rmap_fail(m, "av_beta", "must be >= 0 (got %g); Monaghan's beta of the soil, 0 by default", avb);
    else if (!(kh >= 0))
        rmap_fail(m, "permeability", "must be >= 0 m/s (got %g); the Darcy hydraulic conductivity k_h", kh);
    else if (!(mat->friction >= 0))
        rmap_fail(m, "friction", "must be >= 0 (got %g); the soil-DEM friction coefficient mu_phi", mat->friction);
}

static void read_materials(reader *r, yaml_node_t *n, lahar_case *c)
{
    static const char *const models[] = {"linear", "hertz", "soil", NULL};
    static const char *const soil_only[] = {"friction_angle", "cohesion", "dilatancy", "permeability", "damping",
                                            "av_alpha", "av_beta", NULL};
    static const char *const dem_only[] = {"kn", "kt_ratio", "restitution", NULL};
    rmap top;
    if (rmap_open(r, n, "materials", &top) != 0)
        return;
    int nm = (int)(n->data.mapping.pairs.top - n->data.mapping.pairs.start);
    if (nm == 0) {
        rd_fail(r, n, "materials", "no material defined; add e.g. `rock: {density: 2650, young: 1e8, "
                "restitution: 0.5, friction: 0.5}`");
        return;
    }
    c->materials = calloc((size_t)nm, sizeof *c->materials);
    if (!c->materials) {
        rd_fail(r, n, "materials", "out of memory");
        return;
    }
    for (int i = 0; i < nm && !r->failed; i++) {
        yaml_node_pair_t *p = n->data.mapping.pairs.start + i;
        yaml_node_t *kn = rd_node(r, p->key);
        lahar_material *mat = &c->materials[i];
        if (kn->type != YAML_SCALAR_NODE) {
            rd_fail(r, kn, "materials", "a material name must be a plain name");
            return;
        }
        for (int j = 0; j < i; j++)
            if (strcmp(c->materials[j].name, scalar(kn)) == 0) {
                rd_fail(r, kn, "materials", "material '%s' is defined twice; keep one", scalar(kn));
                return;
            }
        if (strlen(scalar(kn)) >= LAHAR_NAME_MAX) {
            rd_fail(r, kn, "materials", "material name longer than %d characters", LAHAR_NAME_MAX - 1);
            return;
        }
        snprintf(mat->name, sizeof mat->name, "%s", scalar(kn));
        char prefix[KEY_MAX];
        snprintf(prefix, sizeof prefix, "materials.%s", mat->name);
        rmap m;
        if (rmap_open(r, rd_node(r, p->value), prefix, &m) != 0)
            return;
        c->nmaterial = i + 1;
        rmap_section(&m, "materials.NAME");
        mat->density = rmap_num(&m, "density", 1, 0.0, "2650");
        mat->model = (lahar_contact_model)rmap_enum(&m, "model", models, 0, LAHAR_CONTACT_HERTZ);
        if (r->failed)
            return;
        if (mat->model == LAHAR_CONTACT_SOIL) {
            read_soil_material(&m, mat, dem_only);
            continue;
        }
        for (int k = 0; soil_only[k] && !r->failed; k++)
            if (rmap_get(&m, soil_only[k]))
                rmap_fail(&m, soil_only[k], "is a key of an SPH soil (model: soil), but this material uses model: "
                          "%s; remove it or set model: soil", models[mat->model]);
        if (mat->model == LAHAR_CONTACT_HERTZ) {
            if (rmap_get(&m, "kn"))
                rmap_fail(&m, "kn", "is the stiffness of model: linear, but this material uses model: hertz; "
                          "remove kn or set model: linear");
            mat->young = rmap_num(&m, "young", 1, 0.0, "1e8");
            mat->poisson = rmap_num(&m, "poisson", 0, 0.25, "0.25");
        } else {
            if (rmap_get(&m, "young"))
                rmap_fail(&m, "young", "is used by model: hertz, but this material uses model: linear; "
                          "remove young or set model: hertz");
            mat->kn = rmap_num(&m, "kn", 1, 0.0, "1e6");
            mat->poisson = rmap_num(&m, "poisson", 0, 0.25, "0.25");
        }
        mat->kt_ratio = rmap_num(&m, "kt_ratio", 0, 2.0 / 7.0, "0.2857");
        mat->restitution = rmap_num(&m, "restitution", 1, 0.0, "0.5");
        mat->friction = rmap_num(&m, "friction", 1, 0.0, "0.5");
        if (r->failed)
            return;
        if (!(mat->density > 0))
            rmap_fail(&m, "density", "must be > 0 kg/m^3 (got %g)", mat->density);
        else if (mat->model == LAHAR_CONTACT_HERTZ && !(mat->young > 0))
            rmap_fail(&m, "young", "must be > 0 Pa (got %g); Young's modulus, e.g. 1e8", mat->young);
        else if (!(mat->poisson >= 0 && mat->poisson < 0.5))
            rmap_fail(&m, "poisson", "must be in [0, 0.5) (got %g)", mat->poisson);
        else if (mat->model == LAHAR_CONTACT_LINEAR && !(mat->kn > 0))
            rmap_fail(&m, "kn", "must be > 0 N/m (got %g)", mat->kn);
        else if (!(mat->kt_ratio > 0))
            rmap_fail(&m, "kt_ratio", "must be > 0 (got %g); 2/7 is the usual choice", mat->kt_ratio);
        else if (!(mat->restitution > 0 && mat->restitution <= 1))
            rmap_fail(&m, "restitution", "must be in (0, 1] (got %g); 1 is elastic, small values are very "
                      "dissipative", mat->restitution);
        else if (!(mat->friction >= 0))
            rmap_fail(&m, "friction", "must be >= 0 (got %g); 0 is frictionless", mat->friction);
    }
}

static void read_dem(reader *r, yaml_node_t *n, lahar_case *c)
{
    snprintf(c->dem_engine, sizeof c->dem_engine, "spheropoly");
    c->dem_dt_safety = 0.02;
    if (!n)
        return;
    rmap m;
    if (rmap_open(r, n, "dem", &m) != 0)
        return;
    rmap_section(&m, "dem");
    rmap_name(&m, "engine", 0, "spheropoly", c->dem_engine);
    yaml_node_t *engine_node = rmap_get(&m, "engine");
    c->dem_engine_line = engine_node ? (int)engine_node->start_mark.line + 1 : 0;
    c->dem_dt_safety = key_num(&m, "dt_safety");
    if (r->failed)
        return;
    /* Stability of the leapfrog on a damped contact spring (omega = 2 pi / T, damping ratio zeta):
     * omega h < 2 (sqrt(1 + zeta^2) - zeta), i.e. h / T < (sqrt(1 + zeta^2) - zeta) / pi; above it a
     * resting contact pumps energy into the body without bound (tests/stress: a disc resting on a
     * floor jumps 7 cm at h / T = 0.29 with e = 0.5). zeta of the most damped pair (the smallest
     * restitution, closed form of dem_node/README.md), 10 % margin for the engine's calibrated
     * damping; the bound is that of the linear law, the Hertz period is defined alike. */
    double e_min = 1.0;
    for (int i = 0; i < c->nmaterial; i++)
        e_min = fmin(e_min, c->materials[i].restitution);
    if (!r->failed && c->nmaterial > 0 && e_min > 0.0 && e_min <= 1.0) {
        double le = log(e_min), zeta = -le / sqrt(M_PI * M_PI + le * le);
        double bound = 0.9 * (sqrt(1.0 + zeta * zeta) - zeta) / M_PI;
        if (c->dem_dt_safety > bound)
            rmap_fail(&m, "dt_safety", "%g is above the stability limit %.3g of the DEM contact integration for "
                      "restitution %g (h / T < (sqrt(1 + zeta^2) - zeta) / pi with 10 %% margin: above it a resting "
                      "contact gains energy); use at most %.2g (0.02 is accurate)", c->dem_dt_safety, bound, e_min,
                      floor(bound * 100.0) / 100.0);
    }
}

/* The instability checks (common/protocol/instability.h); defaults when the section is absent. */
static void read_stability(reader *r, yaml_node_t *n, lahar_case *c)
{
    lahar_stability *s = &c->stability;
    s->density_band[0] = 0.5;
    s->density_band[1] = 2.0;
    s->max_overlap = 0.5;
    s->dt_collapse = 1e-3;
    if (!n)
        return;
    rmap m;
    if (rmap_open(r, n, "stability", &m) != 0)
        return;
    rmap_section(&m, "stability");
    rmap_vec(&m, "density_band", 2, s->density_band, 0, "[0.5, 2.0]");
    if (!r->failed && !(s->density_band[0] > 0.0 && s->density_band[0] < 1.0 && s->density_band[1] > 1.0))
        rmap_fail(&m, "density_band", "must be [lo, hi] with 0 < lo < 1 < hi (got [%g, %g]); it is the band of "
                  "rho / rho0 every particle must stay in, e.g. [0.5, 2.0]", s->density_band[0], s->density_band[1]);
    s->max_overlap = key_num(&m, "max_overlap");
    s->dt_collapse = key_num(&m, "dt_collapse");
}

/* Coordinated checkpoints (coordinator/README.md "Checkpoints and resume"); none when the
 * section is absent. */
static void read_checkpoint(reader *r, yaml_node_t *n, lahar_case *c)
{
    c->checkpoint_interval = 0.0;
    c->checkpoint_keep = 2;
    if (!n)
        return;
    rmap m;
    if (rmap_open(r, n, "checkpoint", &m) != 0)
        return;
    rmap_section(&m, "checkpoint");
    c->checkpoint_interval = key_num(&m, "interval");
    double keep = key_num(&m, "keep");
    if (!r->failed)
        c->checkpoint_keep = (int)keep;
}

/* --- bodies -------------------------------------------------------------------------------------- */

enum { SH_SPHERE, SH_DISC, SH_BOX, SH_SEGMENT, SH_POLYLINE, SH_POLYGON, SH_POLYHEDRON, SH_PLANE, SH_STL, SH_N };
static const char *const shape_names[] = {"sphere", "disc", "box", "segment", "polyline", "polygon",
                                          "polyhedron", "plane", "stl", NULL};
/* 2: 2D only, 3: 3D only, 0: both */
static const int shape_dim[SH_N] = {3, 2, 0, 0, 2, 2, 3, 3, 3};
static const int shape_fixed_only[SH_N] = {0, 0, 0, 0, 1, 0, 0, 1, 1};
static const char *const motion_names[] = {"free", "fixed", "prescribed", NULL};

/* Read a list of points (each `dim` numbers) into a new array of 3-vectors (z = 0 in 2D). */
static double (*read_points(reader *r, yaml_node_t *n, const char *key, int dim, int *np))[3]
{
    if (r->failed)
        return NULL;
    if (n->type != YAML_SEQUENCE_NODE || seq_len(n) == 0) {
        rd_fail(r, n, key, "expected a non-empty list of points like [[x, y%s], ...], got %s", dim == 3 ? ", z" : "",
                n->type == YAML_SEQUENCE_NODE ? "an empty list" : node_kind(n));
        return NULL;
    }
    int cnt = seq_len(n);
    double (*p)[3] = calloc((size_t)cnt, sizeof *p);
    if (!p) {
        rd_fail(r, n, key, "out of memory");
        return NULL;
    }
    for (int i = 0; i < cnt; i++) {
        char ik[KEY_MAX];
        snprintf(ik, sizeof ik, "%.*s[%d]", KEY_MAX - 16, key, i);
        if (!node_vec(r, seq_item(r, n, i), ik, dim, p[i])) {
            free(p);
            return NULL;
        }
    }
    *np = cnt;
    return p;
}

/* Faces: a list of lists of vertex indices -> face_start (nf + 1) and face_v. */
static int read_faces(reader *r, yaml_node_t *n, const char *key, int **fs, int **fv, int *nf)
{
    if (n->type != YAML_SEQUENCE_NODE || seq_len(n) == 0) {
        rd_fail(r, n, key, "expected a non-empty list of faces like [[0, 1, 2], ...], got %s",
                n->type == YAML_SEQUENCE_NODE ? "an empty list" : node_kind(n));
        return -1;
    }
    int cnt = seq_len(n), total = 0;
    for (int f = 0; f < cnt; f++) {
        yaml_node_t *fn = seq_item(r, n, f);
        if (fn->type != YAML_SEQUENCE_NODE) {
            char ik[KEY_MAX];
            snprintf(ik, sizeof ik, "%.*s[%d]", KEY_MAX - 16, key, f);
            rd_fail(r, fn, ik, "expected a list of vertex indices like [0, 1, 2], got %s", node_kind(fn));
            return -1;
        }
        total += seq_len(fn);
    }
    *fs = calloc((size_t)(unsigned)cnt + 1, sizeof **fs);
    *fv = calloc((size_t)(total ? total : 1), sizeof **fv);
    if (!*fs || !*fv) {
        free(*fs);
        free(*fv);
        rd_fail(r, n, key, "out of memory");
        return -1;
    }
    int k = 0;
    for (int f = 0; f < cnt; f++) {
        yaml_node_t *fn = seq_item(r, n, f);
        (*fs)[f] = k;
        for (int i = 0; i < seq_len(fn); i++) {
            char ik[KEY_MAX + 32];
            snprintf(ik, sizeof ik, "%.*s[%d][%d]", KEY_MAX - 8, key, f, i);
            double v;
            if (node_number(r, seq_item(r, fn, i), ik, &v) != 0 || v != floor(v) || v < 0 || v > INT_MAX) {
                rd_fail(r, seq_item(r, fn, i), ik, "expected a vertex index (an integer >= 0)");
                free(*fs);
                free(*fv);
                return -1;
            }
            (*fv)[k++] = (int)v;
        }
    }
    (*fs)[cnt] = k;
    *nf = cnt;
    return 0;
}

/* Mass properties per identical local shape: thousands of copies of one rock cost one computation. */
typedef struct {
    uint64_t hash;
    int dim;
    lahar_shape local;      /* as built, before the principal transform (the lookup key) */
    lahar_shape principal;  /* moved to the principal frame */
    lahar_mass_props mp;    /* unit density */
} mass_cache_entry;

typedef struct {
    int n, cap;
    mass_cache_entry *e;
} mass_cache;

static uint64_t fnv1a(uint64_t h, const void *data, size_t n)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 1099511628211ull;
    }
    return h;
}

static uint64_t shape_hash(const lahar_shape *s, int dim)
{
    uint64_t h = 1469598103934665603ull;
    h = fnv1a(h, &dim, sizeof dim);
    h = fnv1a(h, &s->radius, sizeof s->radius);
    h = fnv1a(h, &s->nv, sizeof s->nv);
    h = fnv1a(h, &s->nf, sizeof s->nf);
    h = fnv1a(h, s->v, (size_t)s->nv * sizeof *s->v);
    if (s->nf)
        h = fnv1a(h, s->face_v, (size_t)s->face_start[s->nf] * sizeof *s->face_v);
    return h;
}

static int shape_equal(const lahar_shape *a, const lahar_shape *b)
{
    if (a->nv != b->nv || a->ne != b->ne || a->nf != b->nf || a->radius != b->radius)
        return 0;
    if (memcmp(a->v, b->v, (size_t)a->nv * sizeof *a->v) != 0 || memcmp(a->e, b->e, (size_t)a->ne * sizeof *a->e) != 0)
        return 0;
    if (a->nf && (memcmp(a->face_start, b->face_start, ((size_t)a->nf + 1) * sizeof *a->face_start) != 0 ||
                  memcmp(a->face_v, b->face_v, (size_t)a->face_start[a->nf] * sizeof *a->face_v) != 0))
        return 0;
    return 1;
}

static void mass_cache_free(mass_cache *mc)
{
    for (int i = 0; i < mc->n; i++) {
        lahar_shape_free(&mc->e[i].local);
        lahar_shape_free(&mc->e[i].principal);
    }
    free(mc->e);
    memset(mc, 0, sizeof *mc);
}

/* Replace *s (local frame) by its principal-frame version and give its unit-density properties. */
static int mass_cache_apply(mass_cache *mc, lahar_shape *s, int dim, lahar_mass_props *mp, char *err, size_t errlen)
{
    uint64_t h = shape_hash(s, dim);
    for (int i = 0; i < mc->n; i++)
        if (mc->e[i].hash == h && mc->e[i].dim == dim && shape_equal(&mc->e[i].local, s)) {
            lahar_shape_free(s);
            *mp = mc->e[i].mp;
            return lahar_shape_copy(s, &mc->e[i].principal);
        }
    if (lahar_shape_mass_properties(s, dim, mp, err, errlen) != 0)
        return -1;
    if (mc->n == mc->cap) {
        int cap = mc->cap ? 2 * mc->cap : 16;
        mass_cache_entry *t = realloc(mc->e, (size_t)cap * sizeof *t);
        if (!t)
            return -1;
        mc->e = t;
        mc->cap = cap;
    }
    mass_cache_entry *e = &mc->e[mc->n];
    memset(e, 0, sizeof *e);
    if (lahar_shape_copy(&e->local, s) != 0)
        return -1;
    lahar_shape_to_principal(s, mp);
    if (lahar_shape_copy(&e->principal, s) != 0) {
        lahar_shape_free(&e->local);
        return -1;
    }
    e->hash = h;
    e->dim = dim;
    e->mp = *mp;
    mc->n++;
    return 0;
}

/* Build the body's shape in its local frame (coordinates relative to `position`, before the
 * orientation). Returns 0 or -1 (message already reported). */
static int build_shape(reader *r, rmap *m, int kind, int motion, lahar_shape *s)
{
    const int dim = r->dim;
    char key[KEY_MAX], err[512] = "";
    double radius = rmap_num(m, "radius", 1, 0.0, kind == SH_SPHERE || kind == SH_DISC ? "0.05" : "0.005");
    if (r->failed)
        return -1;
    if (!(radius > 0)) {
        rmap_fail(m, "radius", "must be > 0 m (got %g); %s", radius,
                  kind == SH_SPHERE || kind == SH_DISC ? "it is the sphere/disc radius"
                                                       : "it is the sweep (rounding) radius of the shape, small "
                                                         "compared with the body (e.g. 1-5 % of its size)");
        return -1;
    }
    int rc = -1;
    switch (kind) {
    case SH_SPHERE:
    case SH_DISC:
        rc = lahar_shape_make_sphere(s, radius);
        break;
    case SH_BOX: {
        double size[3] = {0, 0, 0}, half[3] = {0, 0, 0};
        rmap_vec(m, "size", dim, size, 1, dim == 3 ? "[0.2, 0.1, 0.1]" : "[0.2, 0.1]");
        if (r->failed)
            return -1;
        for (int k = 0; k < dim; k++) {
            if (!(size[k] > 2.0 * radius)) {
                rmap_fail(m, "size", "every side must be > 2 radius = %g m (got %g); size is the OUTER size, the "
                          "core is size - 2 radius", 2.0 * radius, size[k]);
                return -1;
            }
            half[k] = 0.5 * size[k] - radius;
        }
        rc = dim == 3 ? lahar_shape_make_box(s, half, radius) : lahar_shape_make_box2d(s, half, radius);
        break;
    }
    case SH_PLANE: {
        double size[2] = {0, 0}, nrm[3] = {0, 0, 0}, zero[3] = {0, 0, 0};
        rmap_vec(m, "normal", 3, nrm, 1, "[0, 0, 1]");
        rmap_vec(m, "size", 2, size, 1, "[1.0, 1.0]");
        if (r->failed)
            return -1;
        if (!(v3_norm(v3_load(nrm)) > 0)) {
            rmap_fail(m, "normal", "must not be the zero vector; it is the outward normal of the rectangle");
            return -1;
        }
        if (!(size[0] > 0 && size[1] > 0)) {
            rmap_fail(m, "size", "both sides must be > 0 m (got [%g, %g])", size[0], size[1]);
            return -1;
        }
        rc = lahar_shape_make_plane(s, zero, nrm, size, radius);
        break;
    }
    case SH_SEGMENT:
    case SH_POLYLINE:
    case SH_POLYGON:
    case SH_POLYHEDRON: {
        yaml_node_t *vn = rmap_get(m, "vertices");
        if (!vn) {
            rmap_missing(m, "vertices", dim == 3 ? "[[0, 0, 0], [1, 0, 0], ...]" : "[[0, 0], [1, 0], ...]");
            return -1;
        }
        key_join(m->prefix, "vertices", key);
        int np = 0;
        double (*p)[3] = read_points(r, vn, key, dim, &np);
        if (!p)
            return -1;
        if (kind == SH_SEGMENT) {
            if (np != 2)
                rd_fail(r, vn, key, "a segment has exactly 2 vertices (got %d)", np);
            else if (v3_norm(v3_sub(v3_load(p[0]), v3_load(p[1]))) == 0.0)
                rd_fail(r, vn, key, "the two vertices coincide; use shape: %s for a single point",
                        dim == 3 ? "sphere" : "disc");
            else
                rc = lahar_shape_make_segment(s, p[0], p[1], radius);
        } else if (kind == SH_POLYLINE) {
            int closed = rmap_bool(m, "closed", 0);
            if (!r->failed) {
                rc = lahar_shape_make_polyline(s, (const double(*)[3])p, np, closed, radius, err, sizeof err);
                if (rc != 0)
                    rd_fail(r, vn, key, "%s; fix the points", err);
            }
        } else if (kind == SH_POLYGON) {
            rc = lahar_shape_make_polygon_hull(s, (const double(*)[3])p, np, radius, err, sizeof err);
            if (rc != 0)
                rd_fail(r, vn, key, "%s; a polygon needs 3 or more points not on one line", err);
        } else {
            yaml_node_t *fn = rmap_get(m, "faces");
            if (!fn) {
                rc = lahar_shape_make_hull(s, (const double(*)[3])p, np, radius, err, sizeof err);
                if (rc != 0)
                    rd_fail(r, vn, key, "%s; a polyhedron needs 4 or more points not all in one plane", err);
            } else {
                int *fs = NULL, *fv = NULL, nf = 0;
                char fkey[KEY_MAX];
                key_join(m->prefix, "faces", fkey);
                if (read_faces(r, fn, fkey, &fs, &fv, &nf) == 0) {
                    rc = lahar_shape_make_polyhedron(s, (const double(*)[3])p, np, fs, fv, nf, radius, err, sizeof err);
                    if (rc != 0)
                        rd_fail(r, fn, fkey, "%s; fix the faces or drop `faces:` to use the "
                                "convex hull of the vertices", err);
                    else if (lahar_shape_core_volume(s) <= 0) {
                        rd_fail(r, fn, fkey, "the faces are clockwise seen from outside (the core volume is %g); "
                                "list every face's vertices counter-clockwise seen from outside",
                                lahar_shape_core_volume(s));
                        lahar_shape_free(s);
                        rc = -1;
                    } else if (motion != LAHAR_MOTION_FIXED) {
                        double L = 0;
                        for (int i = 0; i < np; i++)
                            L = fmax(L, v3_norm(v3_load(p[i])));
                        if (!lahar_shape_is_convex(s, 3, 1e-9 * (L > 0 ? L : 1))) {
                            rd_fail(r, fn, fkey, "the polyhedron is not convex, but moving bodies must be convex; "
                                    "drop `faces:` to use the convex hull, or split the body");
                            lahar_shape_free(s);
                            rc = -1;
                        }
                    }
                    free(fs);
                    free(fv);
                }
            }
        }
        free(p);
        break;
    }
    case SH_STL: {
        const char *file = rmap_str(m, "file", 1, NULL, "terrain.stl");
        double scale = rmap_num(m, "scale", 0, 1.0, "0.001");
        if (r->failed)
            return -1;
        if (!(scale > 0)) {
            rmap_fail(m, "scale", "must be > 0 (got %g); it multiplies the STL coordinates, e.g. 0.001 for mm", scale);
            return -1;
        }
        char full[2048];
        if (file[0] == '/')
            snprintf(full, sizeof full, "%s", file);
        else
            snprintf(full, sizeof full, "%s%s", r->dir, file);
        rc = lahar_shape_read_stl(s, full, radius, err, sizeof err);
        if (rc != 0)
            rmap_fail(m, "file", "%s; STL paths are relative to the case file's directory", err);
        else
            lahar_shape_transform(s, NULL, NULL, scale);
        break;
    }
    default:
        break;
    }
    if (rc != 0 && !r->failed)
        rd_fail(r, m->node, m->prefix, "out of memory building the shape");
    return r->failed ? -1 : 0;
}

static void read_body(reader *r, yaml_node_t *n, int i, lahar_case *c, mass_cache *mc)
{
    static const char *const common_keys[] = {"name", "shape", "material", "motion", "position", "orientation",
                                              "velocity", "angular_velocity", "radius", "record_contacts"};
    static const char *const extra[SH_N][3] = {
        [SH_SPHERE] = {NULL},
        [SH_DISC] = {NULL},
        [SH_BOX] = {"size", NULL},
        [SH_SEGMENT] = {"vertices", NULL},
        [SH_POLYLINE] = {"vertices", "closed", NULL},
        [SH_POLYGON] = {"vertices", NULL},
        [SH_POLYHEDRON] = {"vertices", "faces", NULL},
        [SH_PLANE] = {"normal", "size", NULL},
        [SH_STL] = {"file", "scale", NULL},
    };
    const int dim = r->dim;
    char prefix[KEY_MAX];
    snprintf(prefix, sizeof prefix, "bodies[%d]", i);
    rmap m;
    if (rmap_open(r, n, prefix, &m) != 0)
        return;
    lahar_body *b = &c->bodies[i];
    int kind = rmap_enum(&m, "shape", shape_names, 1, SH_SPHERE);
    if (r->failed)
        return;
    const char *keys[16];
    int nk = 0;
    for (size_t k = 0; k < sizeof common_keys / sizeof *common_keys; k++)
        keys[nk++] = common_keys[k];
    for (int k = 0; extra[kind][k]; k++)
        keys[nk++] = extra[kind][k];
    keys[nk] = NULL;
    rmap_check_keys(&m, keys);

    char defname[LAHAR_NAME_MAX];
    snprintf(defname, sizeof defname, "body%d", i);
    rmap_name(&m, "name", 0, defname, b->name);
    for (int j = 0; j < i && !r->failed; j++)
        if (strcmp(c->bodies[j].name, b->name) == 0)
            rmap_fail(&m, "name", "'%s' is already the name of bodies[%d]; body names must be unique", b->name, j);
    if (r->failed)
        return;
    if (shape_dim[kind] && shape_dim[kind] != dim) {
        static const char *const alt[SH_N] = {"disc", "sphere", "", "", "segment or stl", "box or polyhedron",
                                              "polygon", "polyline", "polyline"};
        rmap_fail(&m, "shape", "'%s' is a %dD shape but the case has dimensions: %d; use %s", shape_names[kind],
                  shape_dim[kind], dim, alt[kind]);
        return;
    }
    b->motion = (lahar_motion)rmap_enum(&m, "motion", motion_names, 0, LAHAR_MOTION_FREE);
    b->record_contacts = rmap_bool(&m, "record_contacts", 0);
    const char *mat = rmap_str(&m, "material", 1, NULL, c->nmaterial ? c->materials[0].name : "rock");
    if (r->failed)
        return;
    if (shape_fixed_only[kind] && b->motion != LAHAR_MOTION_FIXED) {
        rmap_fail(&m, "shape", "'%s' bodies can only be walls: add `motion: fixed`%s", shape_names[kind],
                  kind == SH_STL ? " (STL surfaces may be open and non-convex)" : "");
        return;
    }
    b->material = lahar_case_find_material(c, mat);
    if (b->material < 0) {
        const char *names[64];
        int nn = 0;
        for (int k = 0; k < c->nmaterial && nn < 63; k++)
            names[nn++] = c->materials[k].name;
        names[nn] = NULL;
        char list[512];
        join_names(names, list, sizeof list);
        const char *near = closest_name(mat, names);
        if (nn == 0)
            rmap_fail(&m, "material", "unknown material '%s'; define it in the materials: section", mat);
        else if (near)
            rmap_fail(&m, "material", "unknown material '%s'; did you mean '%s'? (materials: %s)", mat, near, list);
        else
            rmap_fail(&m, "material", "unknown material '%s'; define it in materials: (defined: %s)", mat, list);
        return;
    }
    if (c->materials[b->material].model == LAHAR_CONTACT_SOIL) {
        rmap_fail(&m, "material", "'%s' is an SPH soil (model: soil); a body needs a DEM material (model: hertz or "
                  "linear)", mat);
        return;
    }

    double pos[3] = {0, 0, 0}, vel[3] = {0, 0, 0}, omega[3] = {0, 0, 0};
    rmap_vec(&m, "position", dim, pos, 0, "");
    quat qu = q_identity();
    yaml_node_t *on = rmap_get(&m, "orientation");
    if (on && !r->failed) {
        static const char *const okeys3[] = {"axis", "angle_deg", NULL};
        static const char *const okeys2[] = {"angle_deg", NULL};
        char ok[KEY_MAX];
        key_join(prefix, "orientation", ok);
        rmap om;
        if (rmap_open(r, on, ok, &om) == 0) {
            rmap_check_keys(&om, dim == 3 ? okeys3 : okeys2);
            double axis[3] = {0, 0, 1};
            if (dim == 3)
                rmap_vec(&om, "axis", 3, axis, 0, "");
            double ang = rmap_num(&om, "angle_deg", 1, 0.0, "30");
            if (!r->failed && !(v3_norm(v3_load(axis)) > 0))
                rmap_fail(&om, "axis", "must not be the zero vector");
            qu = q_axis_angle(v3_normalize(v3_load(axis)), ang * M_PI / 180.0);
        }
    }
    int has_v = rmap_vec(&m, "velocity", dim, vel, 0, "");
    int has_w = 0;
    if (dim == 3)
        has_w = rmap_vec(&m, "angular_velocity", 3, omega, 0, "");
    else if (rmap_get(&m, "angular_velocity")) {
        omega[2] = rmap_num(&m, "angular_velocity", 0, 0.0, "");
        has_w = 1;
    }
    if (r->failed)
        return;
    if (b->motion == LAHAR_MOTION_FIXED && (has_v || has_w)) {
        rmap_fail(&m, has_v ? "velocity" : "angular_velocity", "a fixed body does not move; remove it, or use "
                  "`motion: prescribed` for a wall that moves at a given velocity");
        return;
    }

    lahar_shape *s = &b->shape;
    if (build_shape(r, &m, kind, b->motion, s) != 0)
        return;
    double R[3][3];
    q_to_rotmat(qu, R);
    if (b->motion == LAHAR_MOTION_FIXED) {
        /* walls keep world-frame geometry with identity orientation, mass 0 marks "immovable" */
        lahar_shape_transform(s, (const double(*)[3])R, pos, 1.0);
        b->q[0] = 1.0;
        /* the test costs faces x vertices: large meshes (terrain) are marked non-convex, which
         * only means the engine treats them with the general mesh path */
        b->convex = (double)s->nf * s->nv <= 5e7 && lahar_shape_is_convex(s, dim, 1e-9 * (s->radius + 1.0));
        return;
    }
    char err[256] = "";
    lahar_mass_props mp;
    if (mass_cache_apply(mc, s, dim, &mp, err, sizeof err) != 0) {
        rd_fail(r, n, prefix, "cannot compute mass properties: %s", err[0] ? err : "out of memory");
        return;
    }
    double rho = c->materials[b->material].density;
    b->convex = 1;
    b->mass = rho * mp.volume;
    for (int k = 0; k < 3; k++)
        b->inertia[k] = rho * mp.inertia[k];
    vec3 com = q_rotate(qu, v3_load(mp.com));
    v3_store(v3_add(v3_load(pos), com), b->x);
    quat qb = q_normalize(q_mul(qu, q_from_rotmat((const double(*)[3])mp.axes)));
    q_store(qb, b->q);
    memcpy(b->v, vel, sizeof vel);
    memcpy(b->w, omega, sizeof omega);
}

static void read_bodies(reader *r, yaml_node_t *n, lahar_case *c, mass_cache *mc, int *line)
{
    if (n->type != YAML_SEQUENCE_NODE) {
        rd_fail(r, n, "bodies", "expected a list of bodies (lines starting with `- `), got %s", node_kind(n));
        return;
    }
    int nb = seq_len(n);
    c->bodies = calloc((size_t)(nb ? nb : 1), sizeof *c->bodies);
    if (!c->bodies) {
        rd_fail(r, n, "bodies", "out of memory");
        return;
    }
    for (int i = 0; i < nb && !r->failed; i++) {
        c->nbody = i + 1;
        yaml_node_t *bn = seq_item(r, n, i);
        line[i] = (int)bn->start_mark.line + 1;
        read_body(r, bn, i, c, mc);
    }
}

/* terrain: {file | points, material, radius, name}: one fixed body appended to the bodies, a chain
 * of segments (2D: the points, or a CSV of x,y) or two triangles per grid cell (3D: an ESRI ASCII
 * grid .asc); terrain.h. The polyline / grid stays in the reader for sph.blocks[i].between. */
static void read_terrain(reader *r, yaml_node_t *n, lahar_case *c)
{
    if (!n || r->failed)
        return;
    r->terrain_node = n;
    rmap m;
    if (rmap_open(r, n, "terrain", &m) != 0)
        return;
    rmap_section(&m, "terrain");
    const int dim = r->dim;
    char name[LAHAR_NAME_MAX];
    rmap_name(&m, "name", 0, "terrain", name);
    const char *mat = rmap_str(&m, "material", 1, NULL, c->nmaterial ? c->materials[0].name : "bed");
    double radius = rmap_num(&m, "radius", 1, 0.0, "0.05");
    yaml_node_t *fn = rmap_get(&m, "file"), *pn = rmap_get(&m, "points");
    if (r->failed)
        return;
    if (!(radius > 0)) {
        rmap_fail(&m, "radius", "must be > 0 m (got %g); it is the sweep radius of the terrain surface (the "
                  "surface lies radius above the points), e.g. dx/4", radius);
        return;
    }
    if (lahar_case_find_body(c, name) >= 0) {
        rmap_fail(&m, "name", "'%s' is already the name of a body; give the terrain another name", name);
        return;
    }
    int mi = lahar_case_find_material(c, mat);
    if (mi < 0 || c->materials[mi].model == LAHAR_CONTACT_SOIL) {
        rmap_fail(&m, "material", mi < 0 ? "unknown material '%s'; define it in the materials: section"
                                         : "'%s' is an SPH soil; the terrain needs a DEM material (model: hertz or "
                                           "linear; its friction is mu_phi against soil)", mat);
        return;
    }
    if (!!fn == !!pn) {
        rd_fail(r, n, "terrain", dim == 2 ? "give exactly one of points: [[x, y], ...] or file: profile.csv"
                                          : "give file: terrain.asc (an ESRI ASCII grid)");
        return;
    }
    if (dim == 3 && pn) {
        rmap_fail(&m, "points", "a 3D terrain is a heightmap: give file: terrain.asc (an ESRI ASCII grid)");
        return;
    }
    char err[1024] = "", full[2048] = "";
    if (fn) {
        const char *file = rmap_str(&m, "file", 1, NULL, "terrain.asc");
        if (r->failed)
            return;
        snprintf(full, sizeof full, "%s%s", file[0] == '/' ? "" : r->dir, file);
    }
    lahar_shape s;
    int rc;
    if (dim == 2) {
        if (pn) {
            r->terrain_pts = read_points(r, pn, "terrain.points", 2, &r->terrain_npts);
            if (!r->terrain_pts)
                return;
        } else if (lahar_profile_read_csv(full, &r->terrain_pts, &r->terrain_npts, err, sizeof err) != 0) {
            rmap_fail(&m, "file", "%s (paths are relative to the case file's directory)", err);
            return;
        }
        rc = lahar_shape_make_polyline(&s, (const double(*)[3])r->terrain_pts, r->terrain_npts, 0, radius, err,
                                       sizeof err);
        if (rc != 0) {
            rd_fail(r, pn ? pn : fn, pn ? "terrain.points" : "terrain.file", "%s; fix the points", err);
            return;
        }
    } else {
        if (lahar_heightmap_read_asc(full, &r->terrain_hm, err, sizeof err) != 0) {
            rmap_fail(&m, "file", "%s (paths are relative to the case file's directory)", err);
            return;
        }
        if (lahar_heightmap_shape(&r->terrain_hm, radius, &s, err, sizeof err) != 0) {
            rmap_fail(&m, "file", "%s: %s", full, err);
            return;
        }
    }
    lahar_body *nb = realloc(c->bodies, ((size_t)c->nbody + 1) * sizeof *nb);
    if (!nb) {
        lahar_shape_free(&s);
        rd_fail(r, n, "terrain", "out of memory");
        return;
    }
    c->bodies = nb;
    lahar_body *b = &c->bodies[c->nbody++];
    memset(b, 0, sizeof *b);
    r->terrain_radius = radius;
    snprintf(b->name, sizeof b->name, "%s", name);
    b->material = mi;
    b->motion = LAHAR_MOTION_FIXED;
    b->shape = s;
    b->q[0] = 1.0;
    b->convex = 0; /* the general mesh / polyline path */
}

/* Bodies must not interpenetrate at t = 0 (walls may meet each other). */
static void check_overlaps(reader *r, yaml_node_t *bodies, lahar_case *c)
{
    int n = c->nbody;
    double (*ctr)[4] = malloc((size_t)(n ? n : 1) * sizeof *ctr); /* bounding sphere centre, radius */
    if (!ctr) {
        rd_fail(r, bodies, "bodies", "out of memory");
        return;
    }
    for (int i = 0; i < n; i++) {
        const lahar_body *b = &c->bodies[i];
        const lahar_shape *s = &b->shape;
        double lo[3], hi[3];
        for (int k = 0; k < 3; k++) {
            lo[k] = INFINITY;
            hi[k] = -INFINITY;
        }
        for (int v = 0; v < s->nv; v++) {
            vec3 w = geom_world_vertex(s, b->x, b->q, v);
            for (int k = 0; k < 3; k++) {
                lo[k] = fmin(lo[k], v3_get(w, k));
                hi[k] = fmax(hi[k], v3_get(w, k));
            }
        }
        for (int k = 0; k < 3; k++)
            ctr[i][k] = 0.5 * (lo[k] + hi[k]);
        ctr[i][3] = 0.5 * sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                               (hi[2] - lo[2]) * (hi[2] - lo[2])) + s->radius;
    }
    for (int j = 0; j < n && !r->failed; j++)
        for (int i = 0; i < j && !r->failed; i++) {
            const lahar_body *a = &c->bodies[i], *b = &c->bodies[j];
            if (a->motion != LAHAR_MOTION_FREE && b->motion != LAHAR_MOTION_FREE)
                continue;
            double dx = ctr[i][0] - ctr[j][0], dy = ctr[i][1] - ctr[j][1], dz = ctr[i][2] - ctr[j][2];
            if (sqrt(dx * dx + dy * dy + dz * dz) > ctr[i][3] + ctr[j][3])
                continue;
            double d = geom_body_core_distance(&a->shape, a->x, a->q, &b->shape, b->x, b->q);
            double halo = a->shape.radius + b->shape.radius;
            /* touching is fine, and so is an overlap below 1e-6 of the radii (rounding of
             * coordinates written with a few digits); anything more starts with a force kick */
            if (d < halo * (1.0 - 1e-6)) {
                char key[KEY_MAX];
                int listed = j < seq_len(bodies);
                snprintf(key, sizeof key, listed ? "bodies[%d]" : "terrain", j);
                rd_fail(r, listed ? seq_item(r, bodies, j) : r->terrain_node, key, "'%s' overlaps '%s' (bodies[%d]) by %.3g m at t = 0 (core "
                        "distance %.6g m < sum of radii %.6g m); move the bodies apart", b->name, a->name, i,
                        halo - d, d, halo);
            }
        }
    free(ctr);
}

/* --- sph: the fluid, its particle blocks and the coupling ------------------------------------ */

/* The solver core does not have these yet (sph_node/fluid/sph_fluid.h): a case asking for them is
 * rejected instead of silently running without them. Flip when the solver grows them. */
#define LAHAR_SPH_HAVE_SHEPARD 1
#define LAHAR_SPH_HAVE_SPS 1
/* the coupling (sph_node/coupling/sph_coupling.h) uses eps = dx/2 and the kernel's support */
#define LAHAR_SPH_HAVE_HALO 0
#define LAHAR_SPH_HAVE_KAPPA 0

/* Edges of a closed surface are shared by exactly two triangles. Returns 0, or the number of
 * edges that are not (first one in *bad_a, *bad_b), or -1 out of memory. */
static int edge_pair_cmp(const void *x, const void *y)
{
    const int *a = x, *b = y;
    return a[0] != b[0] ? (a[0] > b[0]) - (a[0] < b[0]) : (a[1] > b[1]) - (a[1] < b[1]);
}

static int mesh_open_edges(const int (*tri)[3], int ntri, int *bad_a, int *bad_b)
{
    int ne = 3 * ntri;
    int (*e)[2] = malloc((size_t)(ne ? ne : 1) * sizeof *e);
    if (!e)
        return -1;
    for (int t = 0; t < ntri; t++)
        for (int k = 0; k < 3; k++) {
            int a = tri[t][k], b = tri[t][(k + 1) % 3];
            e[3 * t + k][0] = a < b ? a : b;
            e[3 * t + k][1] = a < b ? b : a;
        }
    qsort(e, (size_t)ne, sizeof *e, edge_pair_cmp);
    int bad = 0;
    for (int i = 0; i < ne;) {
        int j = i;
        while (j < ne && e[j][0] == e[i][0] && e[j][1] == e[i][1])
            j++;
        if (j - i != 2) {
            if (!bad) {
                *bad_a = e[i][0];
                *bad_b = e[i][1];
            }
            bad++;
        }
        i = j;
    }
    free(e);
    return bad;
}

/* Segments p0-p1 and q0-q1 (2D) properly intersect or touch. */
static int seg2_intersect(const double *p0, const double *p1, const double *q0, const double *q1)
{
    double d1 = (q1[0] - q0[0]) * (p0[1] - q0[1]) - (q1[1] - q0[1]) * (p0[0] - q0[0]);
    double d2 = (q1[0] - q0[0]) * (p1[1] - q0[1]) - (q1[1] - q0[1]) * (p1[0] - q0[0]);
    double d3 = (p1[0] - p0[0]) * (q0[1] - p0[1]) - (p1[1] - p0[1]) * (q0[0] - p0[0]);
    double d4 = (p1[0] - p0[0]) * (q1[1] - p0[1]) - (p1[1] - p0[1]) * (q1[0] - p0[0]);
    if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0)))
        return 1;
    return 0;
}

static void check_block_polygon(reader *r, yaml_node_t *pn, const char *key, lahar_particle_block *pb);

static void read_block_polygon(reader *r, yaml_node_t *pn, const char *prefix, lahar_particle_block *pb)
{
    char key[KEY_MAX];
    key_join(prefix, "polygon", key);
    if (r->dim != 2) {
        rd_fail(r, pn, key, "polygon blocks are 2D; in 3D use box or stl (a closed triangulated surface)");
        return;
    }
    int np = 0;
    double (*p)[3] = read_points(r, pn, key, 2, &np);
    if (!p)
        return;
    pb->kind = LAHAR_BLOCK_POLYGON;
    pb->vert = p;
    pb->nvert = np;
    check_block_polygon(r, pn, key, pb);
}

/* A polygon block must be simple, with at least 3 vertices and an area. */
static void check_block_polygon(reader *r, yaml_node_t *pn, const char *key, lahar_particle_block *pb)
{
    double(*p)[3] = pb->vert;
    const int np = pb->nvert;
    if (np < 3) {
        rd_fail(r, pn, key, "a polygon needs at least 3 vertices (got %d)", np);
        return;
    }
    double area = 0;
    for (int i = 0, j = np - 1; i < np; j = i++)
        area += p[j][0] * p[i][1] - p[i][0] * p[j][1];
    area *= 0.5;
    for (int i = 0; i < np && !r->failed; i++)
        for (int j = i + 1; j < np && !r->failed; j++) {
            int i1 = (i + 1) % np, j1 = (j + 1) % np;
            if (j == i1 || i == j1)
                continue; /* neighbouring edges share a vertex */
            if (seg2_intersect(p[i], p[i1], p[j], p[j1]))
                rd_fail(r, pn, key, "edges %d-%d and %d-%d cross each other; a polygon block must be simple (list "
                        "the vertices in order around the region)", i, i1, j, j1);
        }
    if (!r->failed && !(fabs(area) > 0))
        rd_fail(r, pn, key, "the polygon has zero area");
    lahar_particle_block_bounds(pb, 2);
}

static void read_block_stl(reader *r, yaml_node_t *sn, const char *prefix, lahar_particle_block *pb)
{
    static const char *const keys[] = {"file", "scale", "position", NULL};
    char key[KEY_MAX];
    key_join(prefix, "stl", key);
    if (r->dim != 3) {
        rd_fail(r, sn, key, "stl blocks are 3D; in 2D use box or polygon");
        return;
    }
    rmap m;
    if (rmap_open(r, sn, key, &m) != 0)
        return;
    rmap_check_keys(&m, keys);
    const char *file = rmap_str(&m, "file", 1, NULL, "reservoir.stl");
    double scale = rmap_num(&m, "scale", 0, 1.0, "0.001");
    double pos[3] = {0, 0, 0};
    rmap_vec(&m, "position", 3, pos, 0, "");
    if (r->failed)
        return;
    if (!(scale > 0)) {
        rmap_fail(&m, "scale", "must be > 0 (got %g); it multiplies the STL coordinates, e.g. 0.001 for mm", scale);
        return;
    }
    if (strlen(file) >= sizeof pb->source) {
        rmap_fail(&m, "file", "path longer than %d characters", (int)sizeof pb->source - 1);
        return;
    }
    snprintf(pb->source, sizeof pb->source, "%s", file);
    char full[2048], err[512] = "";
    if (file[0] == '/')
        snprintf(full, sizeof full, "%s", file);
    else
        snprintf(full, sizeof full, "%s%s", r->dir, file);
    lahar_shape s;
    if (lahar_shape_read_stl(&s, full, 1.0, err, sizeof err) != 0) {
        rmap_fail(&m, "file", "%s; STL paths are relative to the case file's directory", err[0] ? err : "out of memory");
        return;
    }
    lahar_shape_transform(&s, NULL, NULL, scale);
    lahar_shape_transform(&s, NULL, pos, 1.0);
    pb->kind = LAHAR_BLOCK_MESH;
    pb->nvert = s.nv;
    pb->ntri = s.nf;
    pb->vert = malloc((size_t)s.nv * sizeof *pb->vert);
    pb->tri = malloc((size_t)(s.nf ? s.nf : 1) * sizeof *pb->tri);
    if (!pb->vert || !pb->tri) {
        lahar_shape_free(&s);
        rmap_fail(&m, "file", "out of memory");
        return;
    }
    memcpy(pb->vert, s.v, (size_t)s.nv * sizeof *pb->vert);
    for (int f = 0; f < s.nf; f++)
        for (int k = 0; k < 3; k++)
            pb->tri[f][k] = s.face_v[s.face_start[f] + k];
    lahar_shape_free(&s);
    int ea = 0, eb = 0;
    int open = mesh_open_edges((const int(*)[3])pb->tri, pb->ntri, &ea, &eb);
    if (open < 0)
        rmap_fail(&m, "file", "out of memory");
    else if (open > 0)
        rmap_fail(&m, "file", "'%s' is not a closed surface: %d edges are not shared by exactly two triangles "
                  "(first: between [%g, %g, %g] and [%g, %g, %g]); a fluid region must be watertight", file, open,
                  pb->vert[ea][0], pb->vert[ea][1], pb->vert[ea][2], pb->vert[eb][0], pb->vert[eb][1], pb->vert[eb][2]);
    lahar_particle_block_bounds(pb, 3);
}

/* between: {top: ...}: the region between the terrain (terrain: section) and an upper surface,
 * a polygon in 2D (top: [[x, y], ...] or top: profile.csv), a closed mesh in 3D (top: surface.asc
 * on the terrain's grid); terrain.h. */
static void read_block_between(reader *r, yaml_node_t *bn, const char *prefix, lahar_particle_block *pb)
{
    static const char *const keys[] = {"top", NULL};
    char key[KEY_MAX], tkey[KEY_MAX], err[1024] = "";
    key_join(prefix, "between", key);
    if (!r->terrain_node) {
        rd_fail(r, bn, key, "a region between the terrain and a surface needs a terrain: section");
        return;
    }
    rmap m;
    if (rmap_open(r, bn, key, &m) != 0)
        return;
    rmap_check_keys(&m, keys);
    yaml_node_t *tn = rmap_get(&m, "top");
    if (!tn) {
        rmap_missing(&m, "top", r->dim == 2 ? "[[x, y], ...]  (or a CSV file of x,y)" : "surface.asc");
        return;
    }
    key_join(key, "top", tkey);
    char full[2048] = "";
    if (tn->type == YAML_SCALAR_NODE) {
        const char *file = scalar(tn);
        snprintf(full, sizeof full, "%s%s", file[0] == '/' ? "" : r->dir, file);
        if (strlen(file) < sizeof pb->source)
            snprintf(pb->source, sizeof pb->source, "%s", file);
    }
    if (r->dim == 3) {
        if (tn->type != YAML_SCALAR_NODE) {
            rd_fail(r, tn, tkey, "in 3D the upper surface is an ESRI ASCII grid on the terrain's grid: top: surface.asc");
            return;
        }
        lahar_heightmap top;
        if (lahar_heightmap_read_asc(full, &top, err, sizeof err) != 0) {
            rd_fail(r, tn, tkey, "%s (paths are relative to the case file's directory)", err);
            return;
        }
        if (lahar_heightmap_block(&r->terrain_hm, &top, full, r->terrain_radius + 0.5 * r->dx, pb, err, sizeof err) != 0)
            rd_fail(r, tn, tkey, "%s", err);
        lahar_heightmap_free(&top);
        return;
    }
    double(*t)[3] = NULL;
    int nt = 0;
    if (tn->type == YAML_SCALAR_NODE) {
        if (lahar_profile_read_csv(full, &t, &nt, err, sizeof err) != 0) {
            rd_fail(r, tn, tkey, "%s (paths are relative to the case file's directory)", err);
            return;
        }
    } else if (!(t = read_points(r, tn, tkey, 2, &nt))) {
        return;
    }
    double(*poly)[3] = NULL;
    int np = 0;
    /* no particle closer than the coupling's halo dx/2 to the terrain's surface (a particle
     * starting inside it gets the penalty's kick, which grows as 1/dt) */
    const double lift = r->terrain_radius + 0.5 * r->dx;
    if (lahar_profile_between((const double(*)[3])r->terrain_pts, r->terrain_npts, (const double(*)[3])t, nt, lift,
                              &poly, &np, err, sizeof err) != 0) {
        free(t);
        rd_fail(r, tn, tkey, "%s", err);
        return;
    }
    free(t);
    pb->kind = LAHAR_BLOCK_POLYGON;
    pb->vert = poly;
    pb->nvert = np;
    check_block_polygon(r, tn, tkey, pb);
}

/* phase: water (default) | soil, and for soil the model: soil material it is made of. */
static void read_block_phase(rmap *bm, lahar_particle_block *pb, const char *const *phases, const lahar_case *c)
{
    pb->phase = rmap_enum(bm, "phase", phases, 0, 0);
    pb->material = -1;
    if (bm->r->failed)
        return;
    if (pb->phase == 0) {
        if (rmap_get(bm, "material"))
            rmap_fail(bm, "material", "water blocks take sph.density and sph.viscosity; a material is for phase: soil "
                      "(remove it, or add `phase: soil`)");
        return;
    }
    const char *name = rmap_str(bm, "material", 1, NULL, "sand   (a materials: entry with model: soil)");
    if (bm->r->failed)
        return;
    pb->material = lahar_case_find_material(c, name);
    if (pb->material < 0)
        rmap_fail(bm, "material", "unknown material '%s'; define it in materials: with model: soil", name);
    else if (c->materials[pb->material].model != LAHAR_CONTACT_SOIL)
        rmap_fail(bm, "material", "'%s' is a DEM material; a soil block needs a material with model: soil "
                  "(young, poisson, friction_angle, cohesion, dilatancy)", name);
    for (int j = 0; j < c->nblock - 1 && !bm->r->failed && pb->material >= 0; j++)
        if (c->blocks[j].phase == 1 && c->blocks[j].material != pb->material)
            rmap_fail(bm, "material", "'%s' differs from the soil of sph.blocks[%d] ('%s'); one soil material per "
                      "case is implemented", name, j, c->materials[c->blocks[j].material].name);
}

/* --- per-particle initial fields (libmatheval) ----------------------------------------------- */

/* Parse expression s in x, y, z (libmatheval: + - * / ^, sin, cos, tan, exp, log, sqrt, abs, ...,
 * constants pi, e). Returns the evaluator, or NULL with a reason in why. */
static void *expr_create(const char *s, char *why, size_t nwhy)
{
    char buf[LAHAR_EXPR_MAX];
    if (strlen(s) >= sizeof buf) {
        snprintf(why, nwhy, "longer than %d characters", LAHAR_EXPR_MAX - 1);
        return NULL;
    }
    snprintf(buf, sizeof buf, "%s", s);
    void *ev = evaluator_create(buf);
    if (!ev) {
        snprintf(why, nwhy, "cannot parse '%s' (libmatheval syntax: + - * / ^, sin, cos, exp, log, sqrt, ..., "
                 "constants pi and e, variables x, y, z)", s);
        return NULL;
    }
    char **names = NULL;
    int count = 0;
    evaluator_get_variables(ev, &names, &count);
    for (int k = 0; k < count; k++)
        if (strcmp(names[k], "x") != 0 && strcmp(names[k], "y") != 0 && strcmp(names[k], "z") != 0) {
            snprintf(why, nwhy, "unknown variable '%s' in '%s'; only x, y, z (the particle's position, m) and "
                     "the constants pi, e may appear; write other constants as numbers", names[k], s);
            evaluator_destroy(ev);
            return NULL;
        }
    return ev;
}

/* Check the expression of node n (key for messages) and copy it to out; also evaluates it at the
 * corners and the centre of the block's box: it must be finite there. */
static void check_block_expr(reader *r, yaml_node_t *n, const char *key, const char *s, const lahar_particle_block *pb,
                             char out[LAHAR_EXPR_MAX])
{
    char why[512];
    void *ev = expr_create(s, why, sizeof why);
    if (!ev) {
        rd_fail(r, n, key, "%s", why);
        return;
    }
    for (int k = 0; k < 9 && !r->failed; k++) {
        double x[3];
        for (int a = 0; a < 3; a++)
            x[a] = k == 8 ? 0.5 * (pb->lo[a] + pb->hi[a]) : ((k >> a) & 1 ? pb->hi[a] : pb->lo[a]);
        if (r->dim == 2)
            x[2] = 0.0;
        double v = evaluator_evaluate_x_y_z(ev, x[0], x[1], x[2]);
        if (!isfinite(v))
            rd_fail(r, n, key, "'%s' is not finite at (%g, %g, %g), a point of the block", s, x[0], x[1], x[2]);
    }
    evaluator_destroy(ev);
    snprintf(out, LAHAR_EXPR_MAX, "%s", s);
}

/* The initial-field datasets of an HDF5 file (initial: {file: F.h5}). */
static const char *const init_sets[4] = {"vx", "vy", "vz", "pressure"};

/* Open file `path` and, for k = 0..3 (vx, vy, vz, pressure), read dataset init_sets[k] into
 * out[k] (when out[k] is not NULL and the dataset exists) after checking it holds exactly n values;
 * found[k] = 1 when present. 0, or -1 with a message naming the file and the dataset. */
static int init_file_read(const char *path, int64_t n, double *out[4], int found[4], char *err, size_t errlen)
{
    H5E_auto2_t fn;
    void *data;
    H5Eget_auto2(H5E_DEFAULT, &fn, &data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    int rc = 0;
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0) {
        snprintf(err, errlen, "%s: cannot open as HDF5", path);
        rc = -1;
    }
    for (int k = 0; k < 4 && !rc; k++) {
        found[k] = H5Lexists(f, init_sets[k], H5P_DEFAULT) > 0;
        if (!found[k])
            continue;
        hid_t d = H5Dopen2(f, init_sets[k], H5P_DEFAULT), s = d >= 0 ? H5Dget_space(d) : -1;
        hssize_t m = s >= 0 ? H5Sget_simple_extent_npoints(s) : -1;
        if (d < 0 || s < 0 || m < 0 || H5Sget_simple_extent_ndims(s) != 1) {
            snprintf(err, errlen, "%s: dataset '%s' is not a 1D array of numbers", path, init_sets[k]);
            rc = -1;
        } else if ((int64_t)m != n) {
            snprintf(err, errlen, "%s: dataset '%s' has %lld values, the block has %lld particles (one value per "
                     "particle, in lattice order)", path, init_sets[k], (long long)m, (long long)n);
            rc = -1;
        } else if (out[k] && H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out[k]) < 0) {
            snprintf(err, errlen, "%s: dataset '%s' cannot be read as numbers", path, init_sets[k]);
            rc = -1;
        }
        if (s >= 0)
            H5Sclose(s);
        if (d >= 0)
            H5Dclose(d);
    }
    if (f >= 0)
        H5Fclose(f);
    H5Eset_auto2(H5E_DEFAULT, fn, data);
    return rc;
}

int lahar_case_block_initial(const lahar_particle_block *pb, const double (*pts)[3], int64_t n, double (*v)[3],
                             double *p, int *has_p, char *err, size_t errlen)
{
    *has_p = pb->pexpr[0] != 0;
    if (pb->init_file[0]) { /* the loader has checked that no expression is given too */
        double *buf = malloc((size_t)(n > 0 ? n : 1) * 4 * sizeof *buf);
        if (!buf) {
            snprintf(err, errlen, "block '%s': out of memory", pb->name);
            return -1;
        }
        double *out[4] = {buf, buf + n, buf + 2 * n, buf + 3 * n};
        int found[4] = {0, 0, 0, 0};
        int rc = init_file_read(pb->init_file, n, out, found, err, errlen);
        for (int64_t i = 0; i < n && !rc; i++) {
            for (int a = 0; a < 3; a++)
                v[i][a] = found[a] ? out[a][i] : pb->v[a];
            if (found[3])
                p[i] = out[3][i];
            for (int k = 0; k < 4; k++)
                if (found[k] && !isfinite(out[k][i])) {
                    snprintf(err, errlen, "%s: dataset '%s' value %lld is not finite", pb->init_file, init_sets[k],
                             (long long)i);
                    rc = -1;
                    break;
                }
        }
        *has_p = found[3];
        free(buf);
        return rc;
    }
    void *ev[4] = {NULL, NULL, NULL, NULL};
    const char *src[4] = {pb->vexpr[0], pb->vexpr[1], pb->vexpr[2], pb->pexpr};
    const char *what[4] = {"velocity[0]", "velocity[1]", "velocity[2]", "pressure"};
    int rc = 0;
    for (int k = 0; k < 4 && !rc; k++)
        if (src[k][0]) {
            char why[512];
            if (!(ev[k] = expr_create(src[k], why, sizeof why))) {
                snprintf(err, errlen, "block '%s': %s: %s", pb->name, what[k], why);
                rc = -1;
            }
        }
    for (int64_t i = 0; i < n && !rc; i++)
        for (int k = 0; k < 4 && !rc; k++) {
            double val = k < 3 ? pb->v[k] : 0.0;
            if (ev[k])
                val = evaluator_evaluate_x_y_z(ev[k], pts[i][0], pts[i][1], pts[i][2]);
            if (!isfinite(val)) {
                snprintf(err, errlen, "block '%s': %s '%s' is not finite at (%g, %g, %g)", pb->name, what[k], src[k],
                         pts[i][0], pts[i][1], pts[i][2]);
                rc = -1;
            } else if (k < 3 && v)
                v[i][k] = val;
            else if (k == 3 && p && ev[3])
                p[i] = val;
        }
    for (int k = 0; k < 4; k++)
        if (ev[k])
            evaluator_destroy(ev[k]);
    return rc;
}

/* velocity: [numbers or expressions] and pressure: (number or expression) of block pb, checked once
 * the block's box is known. */
static void read_block_fields(reader *r, rmap *bm, lahar_particle_block *pb)
{
    const int dim = r->dim;
    yaml_node_t *vn = rmap_get(bm, "velocity"), *pn = rmap_get(bm, "pressure");
    char key[KEY_MAX];
    if (vn && vn->type == YAML_SEQUENCE_NODE && seq_len(vn) == dim) {
        for (int a = 0; a < dim && !r->failed; a++) {
            yaml_node_t *it = seq_item(r, vn, a);
            snprintf(key, sizeof key, "%.*s.velocity[%d]", KEY_MAX - 32, bm->prefix, a & 3);
            if (!it || it->type != YAML_SCALAR_NODE) {
                rd_fail(r, it ? it : vn, key, "expected a number or an expression in x, y, z, got %s",
                        it ? node_kind(it) : "nothing");
                return;
            }
            const char *s = scalar(it);
            char *end = NULL;
            double v = strtod(s, &end);
            while (end && (*end == ' ' || *end == '\t'))
                end++;
            if (end != s && end && *end == '\0' && isfinite(v))
                pb->v[a] = v;
            else
                check_block_expr(r, it, key, s, pb, pb->vexpr[a]);
        }
    } else if (vn)
        rmap_vec(bm, "velocity", dim, pb->v, 0, ""); /* its message */
    yaml_node_t *in = rmap_get(bm, "initial");
    if (in && !r->failed) {
        static const char *const ikeys[] = {"file", NULL};
        key_join(bm->prefix, "initial", key);
        rmap im;
        if (rmap_open(r, in, key, &im) != 0)
            return;
        rmap_check_keys(&im, ikeys);
        const char *file = rmap_str(&im, "file", 1, NULL, "initial.h5");
        if (r->failed)
            return;
        char full[2048];
        if (file[0] == '/')
            snprintf(full, sizeof full, "%s", file);
        else
            snprintf(full, sizeof full, "%s%s", r->dir, file);
        if (strlen(full) >= sizeof pb->init_file) {
            rmap_fail(&im, "file", "path longer than %d characters", (int)sizeof pb->init_file - 1);
            return;
        }
        if (vn || pn) {
            rmap_fail(bm, "initial", "give the initial fields either as velocity:/pressure: keys or in the file, "
                      "not both");
            return;
        }
        memcpy(pb->init_file, full, strlen(full) + 1); /* fits: checked above */
    }
    if (pn && !r->failed) {
        key_join(bm->prefix, "pressure", key);
        if (pn->type != YAML_SCALAR_NODE || !scalar(pn)[0])
            rd_fail(r, pn, key, "expected a number or an expression in x, y, z (Pa), got %s",
                    pn->type == YAML_SCALAR_NODE ? "an empty value" : node_kind(pn));
        else if (pb->phase != 0)
            rd_fail(r, pn, key, "sets the initial pressure of water; block '%s' is soil (its stress starts at 0)",
                    pb->name);
        else
            check_block_expr(r, pn, key, scalar(pn), pb, pb->pexpr);
    }
}

static void read_block_geometry(reader *r, yaml_node_t *n, int i, lahar_case *c, rmap *bm);

static void read_block(reader *r, yaml_node_t *n, int i, lahar_case *c)
{
    rmap bm;
    read_block_geometry(r, n, i, c, &bm);
    if (!r->failed)
        read_block_fields(r, &bm, &c->blocks[i]);
}

static void read_block_geometry(reader *r, yaml_node_t *n, int i, lahar_case *c, rmap *bmo)
{
    static const char *const phases[] = {"water", "soil", NULL};
    static const char *const boxkeys[] = {"lo", "hi", NULL};
    const int dim = r->dim;
    lahar_particle_block *pb = &c->blocks[i];
    char prefix[KEY_MAX], def[LAHAR_NAME_MAX];
    snprintf(prefix, sizeof prefix, "sph.blocks[%d]", i);
    snprintf(def, sizeof def, "block%d", i);
    rmap xm;
    if (rmap_open(r, n, prefix, bmo) != 0)
        return;
    rmap_section(bmo, "sph.blocks[]");
    rmap_name(bmo, "name", 0, def, pb->name);
    for (int j = 0; j < i && !r->failed; j++)
        if (strcmp(c->blocks[j].name, pb->name) == 0)
            rmap_fail(bmo, "name", "'%s' is already the name of sph.blocks[%d]; block names must be unique", pb->name, j);
    read_block_phase(bmo, pb, phases, c);
    yaml_node_t *bx = rmap_get(bmo, "box"), *pg = rmap_get(bmo, "polygon"), *st = rmap_get(bmo, "stl");
    yaml_node_t *bw = rmap_get(bmo, "between");
    if (r->failed)
        return;
    if (!!bx + !!pg + !!st + !!bw != 1) {
        if (!bx && !pg && !st && !bw)
            rmap_missing(bmo, "box", dim == 3 ? "{lo: [0, 0, 0], hi: [0.1, 0.1, 0.1]}  (or polygon: / stl:)"
                                              : "{lo: [0, 0], hi: [0.1, 0.1]}  (or polygon: [[x, y], ...])");
        else
            rd_fail(r, n, prefix, "give exactly one of box, polygon (2D), stl (3D) or between per block");
        return;
    }
    if (bw) {
        read_block_between(r, bw, prefix, pb);
        return;
    }
    if (pg) {
        read_block_polygon(r, pg, prefix, pb);
        return;
    }
    if (st) {
        read_block_stl(r, st, prefix, pb);
        return;
    }
    char bp[KEY_MAX];
    key_join(prefix, "box", bp);
    if (rmap_open(r, bx, bp, &xm) != 0)
        return;
    rmap_check_keys(&xm, boxkeys);
    pb->kind = LAHAR_BLOCK_BOX;
    rmap_vec(&xm, "lo", dim, pb->lo, 1, dim == 3 ? "[0, 0, 0]" : "[0, 0]");
    rmap_vec(&xm, "hi", dim, pb->hi, 1, dim == 3 ? "[0.1, 0.1, 0.1]" : "[0.1, 0.1]");
    for (int k = 0; k < dim && !r->failed; k++)
        if (!(pb->hi[k] > pb->lo[k]))
            rmap_fail(&xm, "hi", "must be > lo in every component (component %d: %g <= %g)", k, pb->hi[k], pb->lo[k]);
}

/* periodic: {x: [lo, hi], ...} */
static void read_periodic(reader *r, yaml_node_t *n, lahar_sph_options *o)
{
    static const char *const keys3[] = {"x", "y", "z", NULL};
    static const char *const keys2[] = {"x", "y", NULL};
    rmap m;
    if (rmap_open(r, n, "sph.periodic", &m) != 0)
        return;
    rmap_check_keys(&m, r->dim == 3 ? keys3 : keys2);
    for (int a = 0; a < r->dim && !r->failed; a++) {
        double iv[2];
        if (!rmap_vec(&m, keys3[a], 2, iv, 0, ""))
            continue;
        if (!(iv[1] > iv[0])) {
            rmap_fail(&m, keys3[a], "the period [lo, hi] must have hi > lo (got [%g, %g])", iv[0], iv[1]);
            return;
        }
        o->periodic[a] = 1;
        o->lo[a] = iv[0];
        o->hi[a] = iv[1];
    }
}

/* Characteristic speed for the default c0: the free-fall speed over the fluid's height under
 * gravity + body force, the fastest initial velocity of a block, or the fastest point of a
 * moving body at t = 0 (|v| + |w| times its farthest core vertex plus its sweep radius): a body
 * faster than the water's sound speed outruns its pressure waves and crosses it (README,
 * "Stability limits": a 20 m/s boulder needs c0 >= 40 m/s). */
static double sph_reference_speed(const lahar_case *c)
{
    double g = 0, vmax = 0, lo = INFINITY, hi = -INFINITY;
    for (int k = 0; k < 3; k++)
        g += (c->gravity[k] + c->sph.body_force[k]) * (c->gravity[k] + c->sph.body_force[k]);
    g = sqrt(g);
    for (int i = 0; i < c->nblock; i++) {
        const lahar_particle_block *b = &c->blocks[i];
        vmax = fmax(vmax, sqrt(b->v[0] * b->v[0] + b->v[1] * b->v[1] + b->v[2] * b->v[2]));
        /* height: extent along the vertical axis (y in 2D, z in 3D) */
        lo = fmin(lo, b->lo[c->dim - 1]);
        hi = fmax(hi, b->hi[c->dim - 1]);
    }
    for (int i = 0; i < c->nbody; i++) {
        const lahar_body *bd = &c->bodies[i];
        if (bd->motion == LAHAR_MOTION_FIXED)
            continue;
        double reach = 0.0;
        for (int k = 0; k < bd->shape.nv; k++)
            reach = fmax(reach, sqrt(bd->shape.v[k][0] * bd->shape.v[k][0] + bd->shape.v[k][1] * bd->shape.v[k][1] +
                                     bd->shape.v[k][2] * bd->shape.v[k][2]));
        reach += bd->shape.radius;
        double v = sqrt(bd->v[0] * bd->v[0] + bd->v[1] * bd->v[1] + bd->v[2] * bd->v[2]),
               w = sqrt(bd->w[0] * bd->w[0] + bd->w[1] * bd->w[1] + bd->w[2] * bd->w[2]);
        vmax = fmax(vmax, v + w * reach);
    }
    double H = hi > lo ? hi - lo : 0.0;
    return fmax(sqrt(2.0 * g * H), vmax);
}

int lahar_body_contains(const lahar_body *bd, int dim, const double x[3])
{
    const lahar_shape *s = &bd->shape;
    vec3 p = v3_load(x), cp;
    int feat;
    if (geom_point_body_core(s, bd->x, bd->q, p, &cp, &feat) < s->radius)
        return 1;
    /* the core's interior: geom_point_body_core measures to its boundary features only */
    return geom_point_in_core(s, bd->convex, dim, bd->x, bd->q, p);
}

/* The bodies a lattice point must stay out of, with the bounding sphere of each about its x to skip
 * the exact test for most points (fixed bodies keep world coordinates with x = 0: the sphere
 * still covers them). A point must also not start inside the coupling's halo eps = dx/2 about a
 * body's surface (sph_coupling.h, Trujillo-Vela et al. 2020 eq. 14): a particle at d < eps starts with an overlap
 * delta = eps - d whose first push, K_n delta with K_n = 0.1 m_min/dt^2 (eq. 15), is an impulse
 * growing as 1/dt: a free body is kicked by it, so that its motion depended on the time step
 * (the boulder pool of `lahar bench`, README "DEM subcycling": kicked up at 0.16 or 0.51 m/s at
 * dt 6.8e-5 or 1.6e-5 s, the runs ended 47 mm apart; with the points moved, 0.06 mm). Such a point
 * of a free body's halo is moved out along the surface normal to d = eps (kept: its fluid belongs
 * next to the body). Fixed and prescribed bodies keep the lattice as it was: their kick goes
 * into the fluid's start-up only, and moving the points there (or dropping them) changed the
 * validated cylinder array's K (2.5 % -> 7.6 % at c = 0.4). A lattice point exactly eps from a
 * surface stays where it is (tolerance 1e-6 dx). */
typedef struct {
    const lahar_case *c;
    double *reach;
    double eps;
    double zone;  /* sph.body_layers > 0: the lattice leaves out the points within zone = body_layers dx
                     of a round body's surface (case_block_layers fills them); else 0 */
} case_lattice_cut;

/* 1 for a body whose core is one point (a sphere in 3D, a disc in 2D). */
static int case_round_body(const lahar_body *bd)
{
    return bd->shape.nv == 1 && bd->shape.ne == 0 && bd->shape.nf == 0 && bd->shape.radius > 0.0;
}

/* The first round body of the case, or -1. */
static int case_first_round_body(const lahar_case *c)
{
    for (int m = 0; m < c->nbody; m++)
        if (case_round_body(&c->bodies[m]))
            return m;
    return -1;
}

/* x - y with the nearest periodic image on the fluid's periodic axes. */
static vec3 case_periodic_sub(const lahar_case *c, const double x[3], vec3 y)
{
    double v[3] = {x[0] - y.x, x[1] - y.y, x[2] - y.z};
    for (int a = 0; a < c->dim; a++)
        if (c->sph.periodic[a]) {
            double L = c->sph.hi[a] - c->sph.lo[a];
            v[a] -= L * floor(v[a] / L + 0.5);
        }
    return v3(v[0], v[1], c->dim == 2 ? 0.0 : v[2]);
}

/* sph.body_layers: the layers of a round body must stay clear of every other round body's layers
 * and of its own periodic images (each point of the zones is filled once). */
static void case_check_body_layers(rmap *m, const lahar_case *c)
{
    const double zone = c->sph.body_layers * c->sph_dx;
    for (int i = 0; i < c->nbody; i++) {
        const lahar_body *bi = &c->bodies[i];
        if (!case_round_body(bi))
            continue;
        vec3 xi = geom_world_vertex(&bi->shape, bi->x, bi->q, 0);
        for (int a = 0; a < c->dim; a++)
            if (c->sph.periodic[a] && 2.0 * (bi->shape.radius + zone) > c->sph.hi[a] - c->sph.lo[a]) {
                rmap_fail(m, "body_layers", "the %d layers around body '%s' (radius %g m + %g m) overlap its periodic "
                          "image along %c (period %g m); lower body_layers or dx", c->sph.body_layers, bi->name,
                          bi->shape.radius, zone, "xyz"[a], c->sph.hi[a] - c->sph.lo[a]);
                return;
            }
        for (int j = 0; j < i; j++) {
            const lahar_body *bj = &c->bodies[j];
            if (!case_round_body(bj))
                continue;
            double xj[3];
            v3_store(geom_world_vertex(&bj->shape, bj->x, bj->q, 0), xj);
            if (v3_norm(case_periodic_sub(c, xj, xi)) < bi->shape.radius + bj->shape.radius + 2.0 * zone) {
                rmap_fail(m, "body_layers", "the %d layers around bodies '%s' and '%s' overlap (their surfaces are "
                          "closer than 2 x %g m); lower body_layers or dx", c->sph.body_layers, bj->name, bi->name,
                          zone);
                return;
            }
        }
    }
}

/* 0 if x lies in a body's solid; else 1, with x moved out of any free body's halo it starts in. */
static int case_lattice_outside_bodies(double x[3], void *ctx)
{
    const case_lattice_cut *k = ctx;
    const double tol = 1e-6 * k->c->sph_dx;
    for (int m = 0; m < k->c->nbody && k->zone > 0.0; m++) {
        const lahar_body *bd = &k->c->bodies[m];
        if (case_round_body(bd) &&
            v3_norm(case_periodic_sub(k->c, x, geom_world_vertex(&bd->shape, bd->x, bd->q, 0))) <
                bd->shape.radius + k->zone - tol)
            return 0; /* within the layers of sph.body_layers (case_block_layers) */
    }
    for (int m = 0; m < k->c->nbody; m++) {
        const lahar_body *bd = &k->c->bodies[m];
        double d2 = 0;
        for (int a = 0; a < 3; a++)
            d2 += (x[a] - bd->x[a]) * (x[a] - bd->x[a]);
        if (d2 > k->reach[m] * k->reach[m])
            continue;
        if (lahar_body_contains(bd, k->c->dim, x))
            return 0;
        vec3 p = v3_load(x), cp;
        int feat;
        const double R = bd->shape.radius, dc = geom_point_body_core(&bd->shape, bd->x, bd->q, p, &cp, &feat);
        /* in the halo of a free body: out to d = eps along the normal */
        if (bd->motion == LAHAR_MOTION_FREE && dc - R < k->eps - tol && dc > 0.0) {
            vec3 q = v3_axpy((R + k->eps) / dc, v3_sub(p, cp), cp);
            x[0] = q.x, x[1] = q.y, x[2] = k->c->dim == 2 ? 0.0 : q.z;
        }
    }
    /* a point moved out of one body's halo may have landed in another's solid */
    for (int m = 0; m < k->c->nbody; m++)
        if (lahar_body_contains(&k->c->bodies[m], k->c->dim, x))
            return 0;
    return 1;
}

/* sph.body_layers = N > 0: after the lattice points (which leave out the zone within N dx of every
 * round body's surface), the points of that zone on N layers concentric with each round body, at
 * r_l = R + (l + 1/2) dx, l = 0 .. N - 1, like the rows of fluid a flat wall sees in the lattice (the
 * first at the halo eps = dx/2, Trujillo-Vela et al. 2020 eq. 14, and at the depths of the coupling's ghost layers,
 * sph_coupling.h). Layer l holds the lattice's share of its shell R + l dx .. R + (l + 1) dx,
 * round(volume / dx^D) points (4 pi / 3 ((R + (l+1) dx)^3 - (R + l dx)^3) / dx^3 in 3D,
 * pi ((R + (l+1) dx)^2 - (R + l dx)^2) / dx^2 = 2 pi r_l / dx in 2D; the outermost layer also the
 * lattice's own excess in the zone's ball, below), spread evenly: a spherical Fibonacci lattice in
 * 3D (z_i = 1 - (2 i + 1) / n, azimuth i times the golden angle pi (3 - sqrt 5); Gonzalez 2010,
 * Math. Geosci. 42:49), equal angles in 2D (every other layer turned by half a step). A lattice cut
 * by a curved surface instead leaves the first row at any distance from 0 to ~dx from it, denser
 * or sparser than a row; the near-wall model sees the difference (cases/README.md, "Sphere
 * array"). Initial particle positions that conform to the body surface are what particle-packing
 * methods aim at for the same reason (Colagrossi, Bouscasse, Antuono & Marrone 2012, Comput. Phys.
 * Commun. 183:1641); concentric layers are the direct form of that for a sphere or disc. Points are
 * wrapped into the period on periodic axes and kept when inside the block
 * and outside every body (free bodies' halos as for the lattice). Continues the count `count`. */
static int64_t case_block_layers(const lahar_case *c, int block, case_lattice_cut *k, int64_t count, int64_t most,
                                 double (*out)[3], int64_t cap)
{
    const double dx = c->sph_dx, golden = M_PI * (3.0 - sqrt(5.0));
    for (int m = 0; m < c->nbody; m++) {
        const lahar_body *bd = &c->bodies[m];
        if (!case_round_body(bd))
            continue;
        const vec3 xc = geom_world_vertex(&bd->shape, bd->x, bd->q, 0);
        const double R = bd->shape.radius, rz = R + c->sph.body_layers * dx;
        /* the lattice beyond the zone holds as many points as the lattice's ball of radius rz leaves
         * out, B, not the ball's volume V_b / dx^D: the outermost layer takes the difference B - V_b,
         * so that the layers and the lattice together hold the fluid's volume / dx^D as the plain
         * lattice would (B counted on the block's lattice lo + (i + 1/2) dx continued beyond it) */
        const double *blo = c->blocks[block].lo;
        int64_t inball = 0;
        int lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
        for (int a = 0; a < c->dim; a++) {
            double xa = v3_get(xc, a);
            lo[a] = (int)floor((xa - rz - blo[a]) / dx - 0.5), hi[a] = (int)ceil((xa + rz - blo[a]) / dx - 0.5);
        }
        for (int i = lo[0]; i <= hi[0]; i++)
            for (int j = lo[1]; j <= hi[1]; j++)
                for (int q = lo[2]; q <= hi[2]; q++) {
                    double ex = blo[0] + (i + 0.5) * dx - xc.x, ey = blo[1] + (j + 0.5) * dx - xc.y;
                    double ez = c->dim == 3 ? blo[2] + (q + 0.5) * dx - xc.z : 0.0;
                    inball += ex * ex + ey * ey + ez * ez < rz * rz;
                }
        const double vball = c->dim == 3 ? 4.0 * M_PI / 3.0 * rz * rz * rz / (dx * dx * dx) : M_PI * rz * rz / (dx * dx);
        for (int l = 0; l < c->sph.body_layers; l++) {
            const double r = R + (l + 0.5) * dx, r0 = R + l * dx, r1 = r0 + dx;
            double vol = c->dim == 3 ? 4.0 * M_PI / 3.0 * (r1 * r1 * r1 - r0 * r0 * r0) / (dx * dx * dx)
                                     : M_PI * (r1 * r1 - r0 * r0) / (dx * dx);
            if (l == c->sph.body_layers - 1)
                vol += (double)inball - vball;
            const int64_t n = vol > 0.0 ? llround(vol) : 0;
            for (int64_t i = 0; i < n; i++) {
                double x[3];
                if (c->dim == 3) {
                    double z = 1.0 - (2.0 * (double)i + 1.0) / (double)n, s = sqrt(fmax(0.0, 1.0 - z * z));
                    double ph = golden * (double)i;
                    x[0] = xc.x + r * s * cos(ph), x[1] = xc.y + r * s * sin(ph), x[2] = xc.z + r * z;
                } else {
                    double ph = 2.0 * M_PI * ((double)i + 0.5 * (l % 2)) / (double)n;
                    x[0] = xc.x + r * cos(ph), x[1] = xc.y + r * sin(ph), x[2] = 0.0;
                }
                for (int a = 0; a < c->dim; a++)
                    if (c->sph.periodic[a]) {
                        double L = c->sph.hi[a] - c->sph.lo[a];
                        x[a] -= L * floor((x[a] - c->sph.lo[a]) / L);
                    }
                if (!lahar_particle_block_contains(&c->blocks[block], c->dim, x) || !case_lattice_outside_bodies(x, k))
                    continue;
                if (out && count < cap)
                    memcpy(out[count], x, sizeof x);
                if (++count == most)
                    return count;
            }
        }
    }
    return count;
}

/* As lahar_case_block_lattice; first_only: stop at the first particle (the loader only needs to
 * know a block is not empty). */
static int64_t case_block_lattice(const lahar_case *c, int block, double (*out)[3], int64_t cap, int first_only)
{
    /* the halo is dx/2 (the only value sph.halo accepts) */
    case_lattice_cut k = {c, malloc((size_t)(c->nbody > 0 ? c->nbody : 1) * sizeof(double)), 0.5 * c->sph_dx, 0.0};
    if (!k.reach)
        return -1;
    for (int m = 0; m < c->nbody; m++) {
        const lahar_body *bd = &c->bodies[m];
        k.reach[m] = 0.0;
        for (int v = 0; v < bd->shape.nv; v++)
            k.reach[m] = fmax(k.reach[m], v3_norm(v3_sub(geom_world_vertex(&bd->shape, bd->x, bd->q, v), v3_load(bd->x))));
        k.reach[m] += bd->shape.radius + k.eps;
    }
    k.zone = c->sph.body_layers * c->sph_dx;
    int64_t count = lahar_particle_block_lattice_keep(&c->blocks[block], c->dim, c->sph_dx, case_lattice_outside_bodies,
                                                      &k, first_only ? 1 : -1, out, cap);
    if (k.zone > 0.0 && !(first_only && count > 0)) {
        k.zone = 0.0; /* the layers themselves: only the bodies' solids (and free bodies' halos) cut them */
        count = case_block_layers(c, block, &k, count, first_only ? 1 : -1, out, cap);
    }
    free(k.reach);
    return count;
}

int64_t lahar_case_block_lattice(const lahar_case *c, int block, double (*out)[3], int64_t cap)
{
    return case_block_lattice(c, block, out, cap, 0);
}

/* Blocks must hold particles; on periodic axes they stay inside the period; two boxes must not
 * overlap (their particles would be created twice). */
static void check_blocks_placement(reader *r, yaml_node_t *bl, lahar_case *c)
{
    const int dim = c->dim;
    const double dx = c->sph_dx;
    for (int i = 0; i < c->nblock && !r->failed; i++) {
        const lahar_particle_block *b = &c->blocks[i];
        char key[KEY_MAX];
        snprintf(key, sizeof key, "sph.blocks[%d]", i);
        yaml_node_t *bn = seq_item(r, bl, i);
        for (int a = 0; a < dim; a++)
            if (c->sph.periodic[a] && (b->lo[a] < c->sph.lo[a] - 1e-9 * dx || b->hi[a] > c->sph.hi[a] + 1e-9 * dx)) {
                rd_fail(r, bn, key, "'%s' reaches outside the period [%g, %g] of axis %c (block [%g, %g]); keep "
                        "blocks inside sph.periodic", b->name, c->sph.lo[a], c->sph.hi[a], "xyz"[a], b->lo[a], b->hi[a]);
                return;
            }
        for (int j = 0; j < i; j++) {
            const lahar_particle_block *o = &c->blocks[j];
            if (b->kind != LAHAR_BLOCK_BOX || o->kind != LAHAR_BLOCK_BOX || b->phase != o->phase)
                continue; /* water may fill the pores of a soil block (Trujillo-Vela et al. 2020 section 2.3) */
            int overlap = 1;
            for (int a = 0; a < dim; a++)
                overlap = overlap && b->lo[a] < o->hi[a] - 1e-9 * dx && o->lo[a] < b->hi[a] - 1e-9 * dx;
            if (overlap) {
                rd_fail(r, bn, key, "'%s' overlaps block '%s' (sph.blocks[%d]); particles would be created twice "
                        "there: make the boxes meet without overlapping", b->name, o->name, j);
                return;
            }
        }
        double size = lahar_particle_block_lattice_size(b, dim, dx);
        if (!(size <= LAHAR_LATTICE_MAX)) {
            rd_fail(r, bn, key, "'%s' spans %g lattice points at dx = %g (more than %g, beyond any machine); check "
                    "its extent and sph.dx", b->name, size, dx, LAHAR_LATTICE_MAX);
            return;
        }
        int64_t np = case_block_lattice(c, i, NULL, 0, 1);
        if (np < 0) {
            rd_fail(r, bn, key, "out of memory");
            return;
        }
        if (np == 0) {
            rd_fail(r, bn, key, "'%s' holds no particle at dx = %g (its region misses every lattice point "
                    "lo + (i + 1/2) dx outside the bodies); enlarge it or lower sph.dx", b->name, dx);
            return;
        }
    }
}

/* The option keys of sph: (everything but dx, density, periodic and blocks) with the key table's
 * defaults; checks that tie keys together are read_sph's. dx = 0: no spacing known (the halo's
 * default dx/2 stays 0). */
static void read_sph_options(rmap *m, lahar_sph_options *o, int dim, double dx)
{
    static const char *const kernels[] = {"cubic", "quintic", "wendland2", NULL};
    static const char *const eos_names[] = {"linear", "tait", NULL};
    static const char *const wall_names[] = {"halfspace", "paper", NULL};
    static const char *const initial_pressure_names[] = {"none", "hydrostatic", NULL};
    static const char *const wall_pressure_names[] = {"penalty", "ghost", NULL};
    static const char *const penalty_stiffness_names[] = {"step", "acoustic", NULL};
    static const char *const scheme_names[] = {"delta", "riemann", NULL}; /* LAHAR_SPH_SCHEME_* */
    int kind = rmap_enum(m, "kernel", kernels, 0, 0);
    snprintf(o->kernel, sizeof o->kernel, "%s", kernels[kind]);
    const kernel_def *kd = kernel_find(o->kernel);
    o->h_over_dx = key_num(m, "h_over_dx");
    o->eos = (lahar_sph_eos)rmap_enum(m, "eos", eos_names, 0, LAHAR_SPH_EOS_LINEAR);
    o->gamma = key_num(m, "gamma");
    o->mu = key_num(m, "viscosity");
    o->alpha = key_num(m, "alpha");
    o->delta = key_num(m, "delta");
    o->cfl = key_num(m, "cfl");
    o->cfl_force = key_num(m, "cfl_force");
    o->cfl_visc = key_num(m, "cfl_visc");
    rmap_vec(m, "body_force", dim, o->body_force, 0, "");
    o->shepard_interval = (int)key_num(m, "shepard_interval");
    o->shifting = key_num(m, "shifting");
    o->sps = rmap_bool(m, "sps", 0);
    o->shifting_density = rmap_bool(m, "shifting_density", 0);
    o->transport_velocity = rmap_bool(m, "transport_velocity", 0);
    o->body_layers = (int)key_num(m, "body_layers");
    o->sps_cs = key_num(m, "sps_cs");
    o->halo = rmap_num(m, "halo", 0, 0.5 * dx, "0.005");
    o->kappa = rmap_num(m, "kappa", 0, kd ? kd->kappa : 2.0, "2");
    o->wall_viscous = (lahar_sph_wall_viscous)rmap_enum(m, "wall_viscous", wall_names, 0, LAHAR_SPH_WALL_HALFSPACE);
    o->initial_pressure = (lahar_sph_initial_pressure)rmap_enum(m, "initial_pressure", initial_pressure_names, 0,
                                                                LAHAR_SPH_INITIAL_PRESSURE_NONE);
    o->wall_pressure = (lahar_sph_wall_pressure)rmap_enum(m, "wall_pressure", wall_pressure_names, 0,
                                                          LAHAR_SPH_WALL_PRESSURE_PENALTY);
    o->penalty_stiffness = (lahar_sph_penalty_stiffness)rmap_enum(m, "penalty_stiffness", penalty_stiffness_names, 0,
                                                                  LAHAR_SPH_PENALTY_STEP);
    o->soil_wall_stress = (lahar_sph_wall_pressure)rmap_enum(m, "soil_wall_stress", wall_pressure_names, 0,
                                                             LAHAR_SPH_WALL_PRESSURE_PENALTY);
    o->scheme = (lahar_sph_scheme)rmap_enum(m, "scheme", scheme_names, 0, LAHAR_SPH_SCHEME_DELTA);
    o->riemann_limiter = key_num(m, "riemann_limiter");
    if (o->scheme == LAHAR_SPH_SCHEME_RIEMANN) { /* its own dissipation replaces delta-SPH and Monaghan's */
        if (!rmap_get(m, "delta"))
            o->delta = 0.0;
        if (!rmap_get(m, "alpha"))
            o->alpha = 0.0;
    }
}

/* lahar_sph_options_default (case.h): read_sph_options on an empty mapping. */
void lahar_sph_options_default(lahar_sph_options *o)
{
    memset(o, 0, sizeof *o);
    yaml_document_t doc;
    char err[256];
    reader r;
    memset(&r, 0, sizeof r);
    r.path = "(defaults)";
    r.err = err;
    r.errlen = sizeof err;
    r.dim = 3;
    if (!yaml_document_initialize(&doc, NULL, NULL, NULL, 1, 1))
        return;
    int id = yaml_document_add_mapping(&doc, NULL, YAML_ANY_MAPPING_STYLE);
    r.doc = &doc;
    rmap m;
    if (id && rmap_open(&r, rd_node(&r, id), "sph", &m) == 0) {
        rmap_section(&m, "sph");
        read_sph_options(&m, o, 3, 0.0);
    }
    yaml_document_delete(&doc);
}

static void read_sph(reader *r, yaml_node_t *n, lahar_case *c)
{
    lahar_sph_options *o = &c->sph;
    c->sph_density = 1000.0;
    if (!n)
        return;
    const int dim = r->dim;
    rmap m;
    if (rmap_open(r, n, "sph", &m) != 0)
        return;
    rmap_section(&m, "sph");
    c->sph_dx = key_num(&m, "dx");
    c->sph_density = key_num(&m, "density");
    r->dx = c->sph_dx;
    if (r->failed)
        return;
    const double dx = c->sph_dx;
    read_sph_options(&m, o, dim, dx);
    const kernel_def *kd = kernel_find(o->kernel);
    yaml_node_t *pn = rmap_get(&m, "periodic");
    if (pn)
        read_periodic(r, pn, o);
    if (r->failed)
        return;
    const double h = o->h_over_dx * dx;
    if (!kd)
        rmap_fail(&m, "kernel", "the kernel table (common/kernels/kernel.h) has no '%s'", o->kernel);
    else if (rmap_get(&m, "gamma") && o->eos != LAHAR_SPH_EOS_TAIT)
        rmap_fail(&m, "gamma", "is the exponent of eos: tait, but the case uses eos: linear; remove gamma or set "
                  "eos: tait");
    else if (o->scheme == LAHAR_SPH_SCHEME_RIEMANN && o->delta != 0.0)
        rmap_fail(&m, "delta", "scheme: riemann carries its own density diffusion (Zhang et al. 2017); remove delta or "
                  "set it to 0, or use scheme: delta");
    else if (o->scheme == LAHAR_SPH_SCHEME_RIEMANN && o->alpha != 0.0)
        rmap_fail(&m, "alpha", "scheme: riemann carries its own dissipation (Zhang et al. 2017); remove alpha or set it "
                  "to 0, or use scheme: delta");
    else if (rmap_get(&m, "riemann_limiter") && o->scheme != LAHAR_SPH_SCHEME_RIEMANN)
        rmap_fail(&m, "riemann_limiter", "is the limiter of scheme: riemann, but the case uses scheme: delta; remove it "
                  "or set scheme: riemann");
    else if (o->shepard_interval > 0 && !LAHAR_SPH_HAVE_SHEPARD)
        rmap_fail(&m, "shepard_interval", "the Shepard filter is not implemented yet; remove the key or set 0");
    else if (o->sps && !LAHAR_SPH_HAVE_SPS)
        rmap_fail(&m, "sps", "SPS turbulence is not implemented yet; remove the key or set false");
    else if (o->body_layers > 0 && case_first_round_body(c) < 0)
        rmap_fail(&m, "body_layers", "places particles on layers around sphere (3D) or disc (2D) bodies, but the case "
                  "has none; remove the key");
    else if (o->shifting_density && !(o->shifting > 0.0))
        rmap_fail(&m, "shifting_density", "corrects the density for the particle shift, but shifting is off; remove it or "
                  "set shifting > 0");
    else if (rmap_get(&m, "sps_cs") && !o->sps)
        rmap_fail(&m, "sps_cs", "is the Smagorinsky constant of sps: true, but sps is off; remove it or set sps: true");
    else if (!(o->kappa > 0 && o->kappa <= 4))
        rmap_fail(&m, "kappa", "must be in (0, 4] (got %g); the coupling acts within kappa h of a body, the kernel's "
                  "support radius (%g for %s) by default", o->kappa, kd->kappa, o->kernel);
    else if (!(o->halo > 0 && o->halo < o->kappa * h))
        rmap_fail(&m, "halo", "must be in (0, kappa h = %g) m (got %g); dx/2 = %g is usual", o->kappa * h, o->halo,
                  0.5 * dx);
    else if (!LAHAR_SPH_HAVE_HALO && fabs(o->halo - 0.5 * dx) > 1e-12 * dx)
        rmap_fail(&m, "halo", "a halo other than dx/2 = %g m is not implemented yet (got %g); remove the key",
                  0.5 * dx, o->halo);
    else if (!LAHAR_SPH_HAVE_KAPPA && fabs(o->kappa - kd->kappa) > 1e-12)
        rmap_fail(&m, "kappa", "a coupling range other than the kernel's support (%g h for %s) is not implemented "
                  "yet (got %g); remove the key", kd->kappa, o->kernel, o->kappa);
    if (r->failed)
        return;
    /* particle shifting moves particles from crowded to sparse places: at a free surface that is
     * outwards. Lahar detects no free surface, so shifting is for flows driven along periodic
     * axes only (no gravity or body force along a closed axis, where water would settle) */
    for (int a = 0; a < dim && o->shifting > 0.0; a++)
        if (!o->periodic[a] && c->gravity[a] + o->body_force[a] != 0.0) {
            rmap_fail(&m, "shifting", "needs a flow without a free surface, but gravity + body_force acts along the "
                      "non-periodic axis %c (water there settles under a free surface, which shifting would push "
                      "outwards); remove shifting or drive the flow along periodic axes only", "xyz"[a]);
            return;
        }
    if (o->body_layers > 0)
        case_check_body_layers(&m, c);
    if (r->failed)
        return;
    for (int a = 0; a < dim && !r->failed; a++) {
        if (!o->periodic[a])
            continue;
        double L = o->hi[a] - o->lo[a], cells = L / dx;
        char ax[2] = {"xyz"[a], 0};
        char pk[KEY_MAX];
        snprintf(pk, sizeof pk, "sph.periodic.%s", ax);
        /* the cell lists need 3 cells of the kernel support per period (sph_particles.h) */
        if (L < 3.0 * kd->kappa * h)
            rd_fail(r, pn, pk, "the period %g m is shorter than 3 kernel supports (3 x %g m); enlarge it or lower dx",
                    L, kd->kappa * h);
        else if (fabs(cells - floor(cells + 0.5)) > 1e-6 * cells)
            rd_fail(r, pn, pk, "the period %g m is not a whole number of particle spacings (%.6g dx): particles "
                    "would bunch or gap at the seam; make it a multiple of dx = %g", L, cells, dx);
    }
    if (r->failed)
        return;

    yaml_node_t *bl = rmap_get(&m, "blocks");
    if (!bl) {
        rmap_missing(&m, "blocks", "[{name: water, box: {lo: [0, 0, 0], hi: [0.1, 0.1, 0.1]}}]");
        return;
    }
    if (bl->type != YAML_SEQUENCE_NODE || seq_len(bl) == 0) {
        rd_fail(r, bl, "sph.blocks", "expected a non-empty list of particle blocks");
        return;
    }
    int nb = seq_len(bl);
    c->blocks = calloc((size_t)nb, sizeof *c->blocks);
    if (!c->blocks) {
        rd_fail(r, bl, "sph.blocks", "out of memory");
        return;
    }
    for (int i = 0; i < nb && !r->failed; i++) {
        c->nblock = i + 1;
        read_block(r, seq_item(r, bl, i), i, c);
    }
    if (r->failed)
        return;

    double uref = sph_reference_speed(c);
    o->c0 = rmap_num(&m, "c0", 0, 10.0 * uref, "20");
    if (r->failed)
        return;
    if (!rmap_get(&m, "c0") && !(uref > 0)) {
        rmap_fail(&m, "c0", "missing required key: the fluid starts at rest with no gravity or body force, so "
                  "there is no default speed of sound; add e.g. `c0: 1.0` (about 10 x the largest expected speed)");
        return;
    }
    if (!(o->c0 > 0)) {
        rmap_fail(&m, "c0", "must be > 0 m/s (got %g); about 10 x the largest expected flow speed", o->c0);
        return;
    }
    /* background pressure p_b (sph_node/fluid/sph_fluid.h): default 0, or rho0 c0^2 with the transport
     * velocity (Adami et al. 2013 take p_b = p0 = rho0 c0^2) */
    o->background_pressure = rmap_num(&m, "background_pressure", 0,
                                      o->transport_velocity ? c->sph_density * o->c0 * o->c0 : 0.0, "1e4");
    if (r->failed)
        return;
    if (!(o->background_pressure >= 0.0)) {
        rmap_fail(&m, "background_pressure", "must be >= 0 Pa (got %g); 0 = off, rho0 c0^2 = %g is usual with "
                  "transport_velocity", o->background_pressure, c->sph_density * o->c0 * o->c0);
        return;
    }
    if (o->transport_velocity) {
        /* the transport velocity moves particles towards sparse places, as shifting does: no free
         * surface, no walls (a body's side has no particles, the background pressure would push the
         * water into it: Adami et al. 2013 put wall particles there), water only */
        const char *why = NULL;
        char buf[256];
        for (int a = 0; a < dim && !why; a++)
            if (!o->periodic[a] && c->gravity[a] + o->body_force[a] != 0.0) {
                snprintf(buf, sizeof buf, "gravity + body_force acts along the non-periodic axis %c (a free surface "
                         "would form, which the background pressure would tear open)", "xyz"[a]);
                why = buf;
            }
        for (int a = 0; a < dim && !why; a++)
            if (!o->periodic[a]) {
                snprintf(buf, sizeof buf, "axis %c is not periodic (water would meet a free surface or a wall there; "
                         "only fully periodic domains are supported)", "xyz"[a]);
                why = buf;
            }
        if (!why && c->nbody > 0)
            why = "the case has bodies (their surfaces have no wall particles for the background pressure)";
        for (int b = 0; b < c->nblock && !why; b++)
            if (c->blocks[b].phase == 1)
                why = "the case has soil (water only)";
        if (!why && o->shifting > 0.0)
            why = "shifting is on too (the transport velocity already regularises the particles; use one of them)";
        if (!why && !(o->background_pressure > 0.0))
            why = "background_pressure is 0 (it drives the transport velocity; omit it for rho0 c0^2)";
        if (why) {
            rmap_fail(&m, "transport_velocity", "needs a fully periodic water-only flow, but %s", why);
            return;
        }
    }
    /* the smallest step this fluid will ask for must stay above time.dt_min */
    double dt_c = o->cfl * h / o->c0, nu = o->mu / c->sph_density;
    double dt_v = nu > 0 ? o->cfl_visc * h * h / nu : INFINITY;
    if (fmin(dt_c, dt_v) < c->dt_min) {
        if (dt_c <= dt_v)
            rmap_fail(&m, "c0", "the acoustic step cfl h / c0 = %g s is below time.dt_min = %g s; lower c0 or dt_min",
                      dt_c, c->dt_min);
        else
            rmap_fail(&m, "viscosity", "the viscous step cfl_visc h^2 / nu = %g s is below time.dt_min = %g s; "
                      "lower the viscosity or dt_min, or raise dx", dt_v, c->dt_min);
        return;
    }
    /* water and soil particles share space where they seep (Trujillo-Vela et al. 2020, section 2.3): a shift of the
     * water by its own particles only would push it into the soil */
    for (int b = 0; b < c->nblock && o->shifting > 0.0; b++)
        if (c->blocks[b].phase == 1) {
            rmap_fail(&m, "shifting", "is for water-only scenes, but block '%s' is soil (water shifted by its "
                      "own particles would be pushed into the soil); remove shifting", c->blocks[b].name);
            return;
        }
    check_blocks_placement(r, bl, c);
    /* initial files: every dataset present holds one value per particle of its block */
    for (int b = 0; b < c->nblock && !r->failed; b++) {
        const lahar_particle_block *pb = &c->blocks[b];
        if (!pb->init_file[0])
            continue;
        char key[KEY_MAX], msg[1400];
        snprintf(key, sizeof key, "sph.blocks[%d].initial.file", b & 0xffff);
        yaml_node_t *bn = seq_item(r, bl, b);
        const int64_t np = lahar_case_block_lattice(c, b, NULL, 0);
        double *none[4] = {NULL, NULL, NULL, NULL};
        int found[4] = {0, 0, 0, 0};
        if (np < 0)
            rd_fail(r, bn, key, "out of memory");
        else if (init_file_read(pb->init_file, np, none, found, msg, sizeof msg) != 0)
            rd_fail(r, bn, key, "%s", msg);
        else if (!found[0] && !found[1] && !found[2] && !found[3])
            rd_fail(r, bn, key, "%s holds none of the datasets vx, vy, vz, pressure", pb->init_file);
        else if (found[3] && pb->phase != 0)
            rd_fail(r, bn, key, "%s: dataset 'pressure' is for water; block '%s' is soil", pb->init_file, pb->name);
        else if (found[2] && c->dim == 2)
            rd_fail(r, bn, key, "%s: dataset 'vz' in a 2D case; remove it", pb->init_file);
    }
}

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
    pr->rate = rmap_num(pm, "rate", 0, 0.0, "1000");
    if (!rmap_vec(pm, "position", v, pr->x, 1, dim == 3 ? "[0.5, 0.3] (x, y of the vertical line)"
                                                           : "[0.5] (x of the vertical line)"))
        return;
    if (!(pr->rate >= 0.0) || !isfinite(pr->rate)) {
        rmap_fail(pm, "rate", "must be >= 0 (got %g): samples per second (0 or absent = every step)", pr->rate);
        return;
    }
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

static void read_probes(reader *r, yaml_node_t *n, lahar_case *c)
{
    static const char *const kinds[] = {"pressure", "level", NULL};
    if (!n || r->failed)
        return;
    if (n->type != YAML_SEQUENCE_NODE) {
        rd_fail(r, n, "probes", "expected a list of probes (lines starting with `- `), got %s", node_kind(n));
        return;
    }
    if (c->nblock == 0) {
        rd_fail(r, n, "probes", "probes read the SPH fluid, but the case has no sph: blocks; remove probes "
                "or add an sph section");
        return;
    }
    int np = seq_len(n);
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
        if (rmap_open(r, seq_item(r, n, i), prefix, &pm) != 0)
            return;
        rmap_section(&pm, "probes[]");
        rmap_name(&pm, "name", 0, def, pr->name);
        for (int j = 0; j < i && !r->failed; j++)
            if (strcmp(c->probes[j].name, pr->name) == 0)
                rmap_fail(&pm, "name", "'%s' is already the name of probes[%d]; probe names must be unique", pr->name, j);
        pr->kind = rmap_enum(&pm, "kind", kinds, 0, LAHAR_PROBE_PRESSURE);
        if (r->failed)
            return;
        if (pr->kind == LAHAR_PROBE_LEVEL) {
            read_level_gauge(r, &pm, c, pr, lo, hi);
            if (r->failed)
                return;
            continue;
        }
        rmap_vec(&pm, "position", dim, pr->x, 1, dim == 3 ? "[0.5, 0.0, 0.01]" : "[0.5, 0.01]");
        pr->size = rmap_num(&pm, "size", 0, 0.0, "0.009");
        pr->rate = rmap_num(&pm, "rate", 0, 0.0, "20000");
        pr->body = -1;
        const char *bname = rmap_str(&pm, "body", 0, NULL, "wall_right");
        if (r->failed)
            return;
        if (!(pr->size >= 0.0) || !isfinite(pr->size)) {
            rmap_fail(&pm, "size", "must be >= 0 (got %g): the sensor's diameter in m (0 = a point)", pr->size);
            return;
        }
        if (!(pr->rate >= 0.0) || !isfinite(pr->rate)) {
            rmap_fail(&pm, "rate", "must be >= 0 (got %g): samples per second (0 or absent = every step)", pr->rate);
            return;
        }
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
static void read_gauges(reader *r, yaml_node_t *tn, yaml_node_t *vn, lahar_case *c)
{
    static const char *const boxkeys[] = {"lo", "hi", NULL};
    static const char *const axes[] = {"x", "y", "z", NULL};
    yaml_node_t *secs[2] = {tn, vn};
    const char *secname[2] = {"trackers", "control_volumes"};
    const int dim = r->dim;
    for (int sct = 0; sct < 2 && !r->failed; sct++) {
        yaml_node_t *n = secs[sct];
        if (!n)
            continue;
        if (n->type != YAML_SEQUENCE_NODE) {
            rd_fail(r, n, secname[sct], "expected a list (lines starting with `- `), got %s", node_kind(n));
            return;
        }
        if (c->nblock == 0) {
            rd_fail(r, n, secname[sct], "%s read the SPH particles, but the case has no sph: blocks", secname[sct]);
            return;
        }
        int cnt = seq_len(n);
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
            if (rmap_open(r, seq_item(r, n, i), prefix, &pm) != 0)
                return;
            rmap_section(&pm, sct == 0 ? "trackers[]" : "control_volumes[]");
            rmap_name(&pm, "name", 0, def, pr->name);
            for (int j = 0; j < c->nprobe - 1 && !r->failed; j++)
                if (strcmp(c->probes[j].name, pr->name) == 0)
                    rmap_fail(&pm, "name", "'%s' is already the name of a probe, tracker or control volume; names "
                              "must be unique", pr->name);
            pr->body = -1;
            pr->rate = rmap_num(&pm, "rate", 0, 0.0, "10");
            if (!r->failed && (!(pr->rate >= 0.0) || !isfinite(pr->rate)))
                rmap_fail(&pm, "rate", "must be >= 0 (got %g): samples per second (0 or absent = every step)",
                          pr->rate);
            if (sct == 0) {
                pr->kind = LAHAR_PROBE_TRACKER;
                rmap_vec(&pm, "position", dim, pr->x, 1, dim == 3 ? "[10.0, 0.0, 5.0]" : "[10.0, 5.0]");
                continue;
            }
            pr->kind = LAHAR_PROBE_CONTROL_VOLUME;
            pr->axis = rmap_enum(&pm, "axis", axes, 0, 0);
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
            key_join(prefix, "box", bk);
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

static void read_output(reader *r, yaml_node_t *n, lahar_case *c)
{
    /* bit i = field_names[i], matching LAHAR_PFIELD_* in output.h */
    static const char *const field_names[] = {"velocity", "density", "pressure", "phase", "id", "stress", NULL};
    static const char *const forces_names[] = {"none", "all", NULL};
    int has_soil = 0;
    for (int b = 0; b < c->nblock; b++)
        has_soil |= c->blocks[b].phase == 1;
    c->output_fields = has_soil ? 0x3f : 0x1f; /* LAHAR_PFIELD_*: all, and stress when there is soil */
    c->output_forces = 1;
    if (!n)
        return;
    rmap m;
    if (rmap_open(r, n, "output", &m) != 0)
        return;
    rmap_section(&m, "output");
    c->output_forces = rmap_enum(&m, "forces", forces_names, 0, 1);
    yaml_node_t *f = rmap_get(&m, "fields");
    if (!f || r->failed)
        return;
    if (f->type != YAML_SEQUENCE_NODE) {
        rd_fail(r, f, "output.fields", "expected a list of field names like [velocity, pressure], got %s", node_kind(f));
        return;
    }
    c->output_fields = 0;
    for (int i = 0; i < seq_len(f) && !r->failed; i++) {
        yaml_node_t *it = seq_item(r, f, i);
        char key[KEY_MAX];
        snprintf(key, sizeof key, "output.fields[%d]", i);
        int found = -1;
        if (it->type == YAML_SCALAR_NODE)
            for (int k = 0; field_names[k]; k++)
                if (strcmp(scalar(it), field_names[k]) == 0)
                    found = k;
        if (found < 0) {
            char list[128];
            join_names(field_names, list, sizeof list);
            const char *near = it->type == YAML_SCALAR_NODE ? closest_name(scalar(it), field_names) : NULL;
            rd_fail(r, it, key, "unknown field%s%s%s; fields are: %s", near ? "; did you mean '" : "",
                    near ? near : "", near ? "'?" : "", list);
            return;
        }
        if (found == 5 && !has_soil) {
            rd_fail(r, it, key, "stress is the effective stress of soil particles, but the case has no soil block "
                    "(phase: soil); remove it");
            return;
        }
        c->output_fields |= 1u << found;
    }
}

static void read_check(reader *r, yaml_node_t *n, lahar_case *c)
{
    if (!n)
        return;
    rmap m, mm;
    if (rmap_open(r, n, "check", &m) != 0)
        return;
    rmap_section(&m, "check");
    const char *ref = rmap_str(&m, "reference", 1, "", "restitution");
    if (r->failed)
        return;
    if (strlen(ref) >= sizeof c->check.reference) {
        rmap_fail(&m, "reference", "longer than %d characters", (int)sizeof c->check.reference - 1);
        return;
    }
    snprintf(c->check.reference, sizeof c->check.reference, "%s", ref);
    c->check.enabled = 1;
    yaml_node_t *mn = rmap_get(&m, "metrics");
    if (!mn)
        return; /* the reference's default metric and bound apply (coordinator/check/check.c) */
    if (rmap_open(r, mn, "check.metrics", &mm) != 0)
        return;
    int nm = (int)(mn->data.mapping.pairs.top - mn->data.mapping.pairs.start);
    if (nm == 0 || nm > 16) {
        rd_fail(r, mn, "check.metrics", "give 1 to 16 metrics as `name: bound` (got %d)", nm);
        return;
    }
    for (int i = 0; i < nm && !r->failed; i++) {
        yaml_node_pair_t *p = mn->data.mapping.pairs.start + i;
        yaml_node_t *k = rd_node(r, p->key);
        if (k->type != YAML_SCALAR_NODE || strlen(scalar(k)) >= LAHAR_NAME_MAX) {
            rd_fail(r, k, "check.metrics", "a metric name must be a plain name shorter than %d characters",
                    LAHAR_NAME_MAX);
            return;
        }
        snprintf(c->check.metric[i].name, LAHAR_NAME_MAX, "%s", scalar(k));
        char key[KEY_MAX];
        snprintf(key, sizeof key, "check.metrics.%s", scalar(k));
        double v = 0;
        if (node_number(r, rd_node(r, p->value), key, &v) != 0)
            return;
        if (!(v >= 0)) {
            rd_fail(r, rd_node(r, p->value), key, "a bound must be >= 0 (got %g); the metric passes when its value "
                    "is <= the bound", v);
            return;
        }
        c->check.metric[i].bound = v;
        c->check.nmetric = i + 1;
    }
}

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

static void read_inlets(reader *r, yaml_node_t *n, lahar_case *c)
{
    if (!n || r->failed)
        return;
    if (n->type != YAML_SEQUENCE_NODE) {
        rd_fail(r, n, "inlets", "expected a list of inlets (lines starting with `- `), got %s", node_kind(n));
        return;
    }
    if (c->nblock == 0) {
        rd_fail(r, n, "inlets", "inlets feed the SPH fluid, but the case has no sph: blocks; add an sph section with "
                "at least one block");
        return;
    }
    if (open_boundary_support(r, n, "inlets", c) != 0)
        return;
    const int ni = seq_len(n);
    if (ni == 0)
        return;
    if (!(c->inlets = calloc((size_t)ni, sizeof *c->inlets))) {
        rd_fail(r, n, "inlets", "out of memory");
        return;
    }
    const int dim = r->dim;
    for (int i = 0; i < ni && !r->failed; i++) {
        lahar_inlet *in = &c->inlets[i];
        c->ninlet = i + 1;
        char prefix[KEY_MAX], def[LAHAR_NAME_MAX];
        snprintf(prefix, sizeof prefix, "inlets[%d]", i);
        snprintf(def, sizeof def, "inlet%d", i);
        rmap m;
        if (rmap_open(r, seq_item(r, n, i), prefix, &m) != 0)
            return;
        rmap_section(&m, "inlets[]");
        rmap_name(&m, "name", 0, def, in->name);
        if (read_section(&m, dim, in->x0, in->e1, in->e2, in->n, "inward") != 0)
            return;
        const int has_lt = rmap_get(&m, "level_hydrograph") != NULL;
        if (has_lt && rmap_get(&m, "level")) {
            rmap_fail(&m, "level_hydrograph", "give either level: H (constant) or level_hydrograph: FILE.csv (t,h), "
                      "not both");
            return;
        }
        in->level = has_lt ? 1.0 : rmap_num(&m, "level", 1, 0.0, "0.1");
        if (has_lt) { /* a level table t,h: the level is its largest value (the slots of the section) */
            char full[2048], err[1400];
            if (inflow_csv(&m, "level_hydrograph", full, sizeof full) != 0)
                return;
            int kind = 0;
            in->nlevel = lahar_hydrograph_read_csv(full, &kind, &in->level_t, &in->level_h, err, (int)sizeof err);
            if (in->nlevel < 0) {
                in->nlevel = 0;
                rmap_fail(&m, "level_hydrograph", "%s (paths are relative to the case file's directory)", err);
                return;
            }
            if (kind != LAHAR_HYDRO_TABLE_H) {
                rmap_fail(&m, "level_hydrograph", "%s: the header must be `t,h` (a level table)", full);
                return;
            }
            in->level = 0.0;
            for (int k = 0; k < in->nlevel; k++) {
                if (!(in->level_h[k] >= 0.0)) {
                    rmap_fail(&m, "level_hydrograph", "%s: row %d (t = %g s) has a negative level %g m", full, k + 1,
                              in->level_t[k], in->level_h[k]);
                    return;
                }
                in->level = fmax(in->level, in->level_h[k]);
            }
        }
        in->t_start = rmap_num(&m, "start", 0, 0.0, "0.0");
        in->t_end = rmap_num(&m, "end", 0, 1e300, "15.0");
        const double layers = rmap_num(&m, "layers", 0, 0.0, "4");
        const double maxp = rmap_num(&m, "max_particles", 0, 0.0, "100000");
        if (r->failed)
            return;
        if (!(in->level > 0.0)) {
            rmap_fail(&m, in->nlevel ? "level_hydrograph" : "level", "must be > 0 (got %g%s): the water depth above the "
                      "section's lowest point, m", in->level, in->nlevel ? " at most" : "");
            return;
        }
        if (!(in->t_end > in->t_start)) {
            rmap_fail(&m, "end", "must be after start (%g s; got %g s): the inflow runs in [start, end)", in->t_start,
                      in->t_end);
            return;
        }
        if (layers != floor(layers) || layers > 64.0 || (rmap_get(&m, "layers") && layers < 1.0)) {
            rmap_fail(&m, "layers", "must be a whole number of buffer rows in 1 .. 64 (got %g); leave it out for the "
                      "kernel support / dx", layers);
            return;
        }
        in->layers = (int)layers;
        if (maxp != floor(maxp) || maxp > 1e12 || (rmap_get(&m, "max_particles") && maxp < 1.0)) {
            rmap_fail(&m, "max_particles", "must be a whole number >= 1 (got %g); leave it out for the estimate from "
                      "the hydrograph", maxp);
            return;
        }
        in->max_particles = (int64_t)maxp;
        const int has_v = rmap_get(&m, "velocity") != NULL, has_g = rmap_get(&m, "gumbel") != NULL,
                  has_h = rmap_get(&m, "hydrograph") != NULL;
        if (has_v + has_g + has_h != 1) {
            rd_fail(r, m.node, prefix, "give exactly one of velocity: U (m/s), gumbel: [a_G, beta_G, mu_G] "
                    "(Trujillo-Vela et al. 2020, eq. 36) or hydrograph: FILE.csv (header t,u or t,Q)%s",
                    has_v + has_g + has_h ? "; it has more than one" : "");
            return;
        }
        /* the buffer only moves forward (rows are created behind it): no backflow through an inlet */
        if (has_v) {
            in->kind = LAHAR_HYDRO_CONSTANT;
            in->velocity = rmap_num(&m, "velocity", 1, 0.0, "0.5");
            if (!r->failed && !(in->velocity >= 0.0)) {
                rmap_fail(&m, "velocity", "must be >= 0 (got %g m/s): the inflow along the inward normal", in->velocity);
                return;
            }
        } else if (has_g) {
            in->kind = LAHAR_HYDRO_GUMBEL;
            rmap_vec(&m, "gumbel", 3, in->gumbel, 1, "[35, 2, 3]");
            if (!r->failed && !(in->gumbel[1] > 0.0)) {
                rmap_fail(&m, "gumbel", "beta_G (the second number) must be > 0 (got %g s)", in->gumbel[1]);
                return;
            }
            if (!r->failed && !(in->gumbel[0] >= 0.0)) {
                rmap_fail(&m, "gumbel", "a_G (the first number) must be >= 0 (got %g m): the inflow is along the inward "
                          "normal", in->gumbel[0]);
                return;
            }
        } else {
            char full[2048], err[1400];
            if (inflow_csv(&m, "hydrograph", full, sizeof full) != 0)
                return;
            in->ntable = lahar_hydrograph_read_csv(full, &in->kind, &in->table_t, &in->table_v, err, (int)sizeof err);
            if (in->ntable < 0) {
                in->ntable = 0;
                rmap_fail(&m, "hydrograph", "%s (paths are relative to the case file's directory)", err);
                return;
            }
            if (in->kind == LAHAR_HYDRO_TABLE_H) {
                rmap_fail(&m, "hydrograph", "%s holds a level (header t,h); give it as level_hydrograph:, and the "
                          "inflow as t,u or t,Q", full);
                return;
            }
            for (int k = 0; k < in->ntable; k++)
                if (!(in->table_v[k] >= 0.0)) {
                    rmap_fail(&m, "hydrograph", "%s: row %d (t = %g s) has a negative value %g; the inflow is along the "
                              "inward normal (no backflow through an inlet)", full, k + 1, in->table_t[k], in->table_v[k]);
                    return;
                }
        }
    }
}

static void read_outlets(reader *r, yaml_node_t *n, lahar_case *c)
{
    if (!n || r->failed)
        return;
    if (n->type != YAML_SEQUENCE_NODE) {
        rd_fail(r, n, "outlets", "expected a list of outlets (lines starting with `- `), got %s", node_kind(n));
        return;
    }
    if (c->nblock == 0) {
        rd_fail(r, n, "outlets", "outlets remove SPH particles, but the case has no sph: blocks");
        return;
    }
    if (open_boundary_support(r, n, "outlets", c) != 0)
        return;
    const int no = seq_len(n);
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
        if (rmap_open(r, seq_item(r, n, i), prefix, &m) != 0)
            return;
        rmap_section(&m, "outlets[]");
        rmap_name(&m, "name", 0, def, o->name);
        if (read_section(&m, r->dim, o->x0, o->e1, o->e2, o->n, "outward") != 0)
            return;
        o->depth = rmap_num(&m, "depth", 0, 1e30, "1.0");
        if (!r->failed && !(o->depth > 0.0))
            rmap_fail(&m, "depth", "must be > 0 (got %g m): how far beyond the section particles are removed", o->depth);
    }
}

static void read_domain(reader *r, yaml_node_t *n, lahar_case *c)
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
    c->has_domain = 1;
}

/* --- entry points ------------------------------------------------------------------------------- */

static void read_case(reader *r, lahar_case *c)
{
    yaml_node_t *root = yaml_document_get_root_node(r->doc);
    if (!root) {
        rd_fail(r, NULL, "", "the case file is empty; a case needs at least dimensions, time and bodies or sph");
        return;
    }
    rmap m;
    if (rmap_open(r, root, "", &m) != 0)
        return;
    rmap_section(&m, "");
    double d = rmap_num(&m, "dimensions", 1, 3.0, "3");
    if (r->failed)
        return;
    if (d != 2.0 && d != 3.0) {
        rmap_fail(&m, "dimensions", "must be 2 or 3 (got %g); 2D scenes live in the x-y plane", d);
        return;
    }
    c->dim = r->dim = (int)d;
    c->gravity[c->dim - 1] = -9.81;
    rmap_vec(&m, "gravity", c->dim, c->gravity, 0, "");
    read_time(r, root, rmap_get(&m, "time"), c);
    yaml_node_t *mat = rmap_get(&m, "materials"), *bodies = rmap_get(&m, "bodies"), *sph = rmap_get(&m, "sph");
    if (!r->failed && (bodies || rmap_get(&m, "terrain")) && !mat)
        rmap_missing(&m, "materials", "{rock: {density: 2650, young: 1e8, restitution: 0.5, friction: 0.5}}");
    if (!r->failed && !bodies && !sph && !rmap_get(&m, "terrain"))
        rd_fail(r, root, "bodies", "the case has neither bodies nor an sph section; add at least one");
    if (mat)
        read_materials(r, mat, c);
    read_dem(r, rmap_get(&m, "dem"), c);
    read_stability(r, rmap_get(&m, "stability"), c);
    read_checkpoint(r, rmap_get(&m, "checkpoint"), c);
    if (bodies && !r->failed) {
        int nb = bodies->type == YAML_SEQUENCE_NODE ? seq_len(bodies) : 0;
        int *line = calloc((size_t)(nb ? nb : 1), sizeof *line);
        mass_cache mc = {0, 0, NULL};
        if (!line)
            rd_fail(r, bodies, "bodies", "out of memory");
        else
            read_bodies(r, bodies, c, &mc, line);
        mass_cache_free(&mc);
        free(line);
    }
    read_terrain(r, rmap_get(&m, "terrain"), c);
    if (bodies && !r->failed)
        check_overlaps(r, bodies, c);
    read_sph(r, sph, c);
    read_probes(r, rmap_get(&m, "probes"), c);
    read_inlets(r, rmap_get(&m, "inlets"), c);
    read_outlets(r, rmap_get(&m, "outlets"), c);
    read_domain(r, rmap_get(&m, "domain"), c);
    read_gauges(r, rmap_get(&m, "trackers"), rmap_get(&m, "control_volumes"), c);
    read_output(r, rmap_get(&m, "output"), c);
    read_check(r, rmap_get(&m, "check"), c);
}

/* The one loader: YAML bytes in memory; `path` names them in messages, relative paths in the case
 * start from base_dir (NULL: the directory of `path`). */
static int case_load_bytes(const char *path, const char *base_dir, const void *data, size_t size, lahar_case *out,
                           char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    if (errlen)
        err[0] = '\0';
    reader r;
    memset(&r, 0, sizeof r);
    r.path = path;
    r.err = err;
    r.errlen = errlen;
    const char *slash = strrchr(path, '/');
    if (base_dir && base_dir[0])
        snprintf(r.dir, sizeof r.dir, "%s/", base_dir);
    else if (slash)
        snprintf(r.dir, sizeof r.dir, "%.*s/", (int)(slash - path), path);
    yaml_parser_t parser;
    yaml_document_t doc;
    if (!yaml_parser_initialize(&parser)) {
        snprintf(err, errlen, "%s: cannot initialise the YAML parser", path);
        return LAHAR_EXIT_BAD_INPUT;
    }
    yaml_parser_set_input_string(&parser, (const unsigned char *)data, size);
    if (!yaml_parser_load(&parser, &doc)) {
        snprintf(err, errlen, "%s:%d: YAML syntax error: %s%s%s (column %d); fix the YAML syntax", path,
                 (int)parser.problem_mark.line + 1, parser.problem ? parser.problem : "unknown problem",
                 parser.context ? " " : "", parser.context ? parser.context : "", (int)parser.problem_mark.column + 1);
        yaml_parser_delete(&parser);
        return LAHAR_EXIT_BAD_INPUT;
    }
    r.doc = &doc;
    snprintf(out->path, sizeof out->path, "%s", path);
    read_case(&r, out);
    free(r.terrain_pts);
    lahar_heightmap_free(&r.terrain_hm);
    yaml_document_delete(&doc);
    yaml_parser_delete(&parser);
    if (r.failed) {
        lahar_case_free(out);
        return LAHAR_EXIT_BAD_INPUT;
    }
    return 0;
}

int lahar_case_load_mem(const char *path, const void *data, size_t size, lahar_case *out, char *err, size_t errlen)
{
    return case_load_bytes(path, NULL, data, size, out, err, errlen);
}

int lahar_case_load_dir(const char *path, const char *base_dir, lahar_case *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    if (errlen)
        err[0] = '\0';
    FILE *fp = fopen(path, "rb");
    if (!fp) {
        snprintf(err, errlen, "%s: cannot open the case file: %s; check the path", path, strerror(errno));
        return LAHAR_EXIT_BAD_INPUT;
    }
    /* the whole file into memory (case files are small), then the one loader */
    char *data = NULL;
    size_t size = 0, cap = 0;
    for (;;) {
        if (size == cap) {
            size_t ncap = cap ? 2 * cap : 16384;
            char *p = realloc(data, ncap);
            if (!p) {
                free(data);
                fclose(fp);
                snprintf(err, errlen, "%s: out of memory reading the case file", path);
                return LAHAR_EXIT_BAD_INPUT;
            }
            data = p;
            cap = ncap;
        }
        size_t n = fread(data + size, 1, cap - size, fp);
        size += n;
        if (n == 0)
            break;
    }
    int rd_err = ferror(fp);
    fclose(fp);
    if (rd_err) {
        free(data);
        snprintf(err, errlen, "%s: cannot read the case file; check the path", path);
        return LAHAR_EXIT_BAD_INPUT;
    }
    int rc = case_load_bytes(path, base_dir, data, size, out, err, errlen);
    free(data);
    return rc;
}

int lahar_case_load_err(const char *path, lahar_case *out, char *err, size_t errlen)
{
    return lahar_case_load_dir(path, NULL, out, err, errlen);
}

int lahar_case_load(const char *path, lahar_case *out)
{
    char err[2048];
    int rc = lahar_case_load_err(path, out, err, sizeof err);
    if (rc != 0)
        fprintf(stderr, "%s\n", err);
    return rc;
}

void lahar_case_free(lahar_case *c)
{
    if (!c)
        return;
    if (c->bodies)
        for (int i = 0; i < c->nbody; i++)
            lahar_shape_free(&c->bodies[i].shape);
    free(c->bodies);
    free(c->materials);
    if (c->blocks)
        for (int i = 0; i < c->nblock; i++)
            lahar_particle_block_free(&c->blocks[i]);
    free(c->blocks);
    free(c->probes);
    for (int i = 0; i < c->ninlet; i++)
        free(c->inlets[i].table_t), free(c->inlets[i].table_v), free(c->inlets[i].level_t), free(c->inlets[i].level_h);
    free(c->inlets);
    free(c->outlets);
    memset(c, 0, sizeof *c);
}

int lahar_case_find_body(const lahar_case *c, const char *name)
{
    for (int i = 0; i < c->nbody; i++)
        if (strcmp(c->bodies[i].name, name) == 0)
            return i;
    return -1;
}

int lahar_case_find_material(const lahar_case *c, const char *name)
{
    for (int i = 0; i < c->nmaterial; i++)
        if (strcmp(c->materials[i].name, name) == 0)
            return i;
    return -1;
}
