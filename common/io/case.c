/* Case file loader (see case.h; every key: case_keys.c, `lahar keys`): the entry points, the top
 * level and the small sections. The other sections have their own files (common/io/README.md).
 *
 * libyaml builds the document (yaml_parser_load: aliases resolve to shared nodes, every node
 * carries its line); the typed accessors of case_reader.c read numbers, vectors, strings and
 * enums with defaults and report the first problem as `file:line: key.path: what; what to do`. */
#include "case.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>

#include "case_reader.h"
#include "errmsg.h"
#include "geometry.h"
#include "terrain.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif


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
    c->t_end = rd_key_num(&m, "end");
    c->dt_max = rd_key_num(&m, "dt_max");
    c->dt_min = rd_key_num(&m, "dt_min");
    c->output_interval = rd_key_num_def(&m, "output_interval", c->t_end / 100.0);
    c->forces_interval = rd_key_num(&m, "forces_interval");
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
    /* the table (case_keys.c, materials.NAME) gives the defaults and ranges; the soil's own are
     * its Poisson ratio (0.3) and mu_phi = tan(friction_angle) */
    mat->constitutive = rd_key_choice(m, "constitutive");
    mat->young = rd_key_num_req(m, "young", 1, NAN);
    mat->poisson = rd_key_num_def(m, "poisson", 0.3);
    double phi = rd_key_num_req(m, "friction_angle", 1, NAN);
    double coh = rd_key_num(m, "cohesion");
    double psi = rd_key_num(m, "dilatancy");
    double kh = rd_key_num(m, "permeability");
    double cd = rd_key_num(m, "damping");
    double ava = rd_key_num(m, "av_alpha"), avb = rd_key_num(m, "av_beta");
    if (m->r->failed)
        return;
    mat->friction = rd_key_num_def(m, "friction", tan(phi * deg));
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
    if (!(phi > 0 || coh > 0))
        rmap_fail(m, "cohesion", "a soil with friction_angle 0 needs cohesion > 0 (it would have no strength)");
    else if (!(psi <= phi))
        rmap_fail(m, "dilatancy", "must be in [0, friction_angle = %g] degrees (got %g); 0 is usual", phi, psi);
}

static void read_materials(reader *r, yaml_node_t *n, lahar_case *c)
{
    static const char *const soil_only[] = {"constitutive", "friction_angle", "cohesion", "dilatancy", "permeability",
                                            "damping", "av_alpha", "av_beta", NULL};
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
            if (strcmp(c->materials[j].name, rd_scalar(kn)) == 0) {
                rd_fail(r, kn, "materials", "material '%s' is defined twice; keep one", rd_scalar(kn));
                return;
            }
        if (strlen(rd_scalar(kn)) >= LAHAR_NAME_MAX) {
            rd_fail(r, kn, "materials", "material name longer than %d characters", LAHAR_NAME_MAX - 1);
            return;
        }
        snprintf(mat->name, sizeof mat->name, "%s", rd_scalar(kn));
        char prefix[KEY_MAX];
        snprintf(prefix, sizeof prefix, "materials.%s", mat->name);
        rmap m;
        if (rmap_open(r, rd_node(r, p->value), prefix, &m) != 0)
            return;
        c->nmaterial = i + 1;
        rmap_section(&m, "materials.NAME");
        mat->density = rd_key_num(&m, "density");
        mat->model = (lahar_contact_model)rd_key_choice(&m, "model");
        if (r->failed)
            return;
        if (mat->model == LAHAR_CONTACT_SOIL) {
            read_soil_material(&m, mat, dem_only);
            continue;
        }
        for (int k = 0; soil_only[k] && !r->failed; k++)
            if (rmap_get(&m, soil_only[k]))
                rmap_fail(&m, soil_only[k], "is a key of an SPH soil (model: soil), but this material uses model: "
                          "%s; remove it or set model: soil", lahar_key_find(m.sec, "model")->choices[mat->model]);
        if (mat->model == LAHAR_CONTACT_HERTZ) {
            if (rmap_get(&m, "kn"))
                rmap_fail(&m, "kn", "is the stiffness of model: linear, but this material uses model: hertz; "
                          "remove kn or set model: linear");
            mat->young = rd_key_num_req(&m, "young", 1, NAN);
        } else {
            if (rmap_get(&m, "young"))
                rmap_fail(&m, "young", "is used by model: hertz, but this material uses model: linear; "
                          "remove young or set model: hertz");
            mat->kn = rd_key_num_req(&m, "kn", 1, NAN);
        }
        /* the table (case_keys.c, materials.NAME) gives the defaults and ranges */
        mat->poisson = rd_key_num_def(&m, "poisson", 0.25);
        mat->kt_ratio = rd_key_num_def(&m, "kt_ratio", 2.0 / 7.0);
        mat->restitution = rd_key_num_req(&m, "restitution", 1, NAN);
        mat->friction = rd_key_num_req(&m, "friction", 1, NAN);
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
    c->dem_dt_safety = rd_key_num(&m, "dt_safety");
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
    s->max_overlap = rd_key_num(&m, "max_overlap");
    s->dt_collapse = rd_key_num(&m, "dt_collapse");
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
    c->checkpoint_interval = rd_key_num(&m, "interval");
    double keep = rd_key_num(&m, "keep");
    if (!r->failed)
        c->checkpoint_keep = (int)keep;
}

static void read_output(reader *r, yaml_node_t *n, lahar_case *c)
{
    /* bit i = field_names[i], matching LAHAR_PFIELD_* in output.h */
    static const char *const field_names[] = {"velocity", "density", "pressure", "phase", "id", "stress", NULL};
    int has_soil = 0;
    for (int b = 0; b < c->nblock; b++)
        has_soil |= c->blocks[b].phase == 1;
    c->output_fields = has_soil ? 0x3f : 0x1f; /* LAHAR_PFIELD_*: all, and stress when there is soil */
    c->output_forces = 1;
    c->output_in_place = 0;
    if (!n)
        return;
    rmap m;
    if (rmap_open(r, n, "output", &m) != 0)
        return;
    rmap_section(&m, "output");
    c->output_forces = rd_key_choice(&m, "forces");
    c->output_in_place = !rd_key_bool(&m, "twins");
    yaml_node_t *f = rmap_get(&m, "fields");
    if (!f || r->failed)
        return;
    if (f->type != YAML_SEQUENCE_NODE) {
        rd_fail(r, f, "output.fields", "expected a list of field names like [velocity, pressure], got %s", rd_node_kind(f));
        return;
    }
    c->output_fields = 0;
    for (int i = 0; i < rd_seq_len(f) && !r->failed; i++) {
        yaml_node_t *it = rd_seq_item(r, f, i);
        char key[KEY_MAX];
        snprintf(key, sizeof key, "output.fields[%d]", i);
        int found = -1;
        if (it->type == YAML_SCALAR_NODE)
            for (int k = 0; field_names[k]; k++)
                if (strcmp(rd_scalar(it), field_names[k]) == 0)
                    found = k;
        if (found < 0) {
            char list[128];
            rd_join_names(field_names, list, sizeof list);
            const char *near = it->type == YAML_SCALAR_NODE ? rd_closest_name(rd_scalar(it), field_names) : NULL;
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
        if (k->type != YAML_SCALAR_NODE || strlen(rd_scalar(k)) >= LAHAR_NAME_MAX) {
            rd_fail(r, k, "check.metrics", "a metric name must be a plain name shorter than %d characters",
                    LAHAR_NAME_MAX);
            return;
        }
        snprintf(c->check.metric[i].name, LAHAR_NAME_MAX, "%s", rd_scalar(k));
        char key[KEY_MAX];
        snprintf(key, sizeof key, "check.metrics.%s", rd_scalar(k));
        double v = 0;
        if (rd_number(r, rd_node(r, p->value), key, &v) != 0)
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
    if (bodies && !r->failed)
        case_read_bodies(r, bodies, c);
    case_read_terrain(r, rmap_get(&m, "terrain"), c);
    if (bodies && !r->failed)
        case_check_overlaps(r, bodies, c);
    case_read_sph(r, sph, c);
    case_read_probes(r, rmap_get(&m, "probes"), c);
    case_read_inlets(r, rmap_get(&m, "inlets"), c);
    case_read_outlets(r, rmap_get(&m, "outlets"), c);
    case_read_domain(r, rmap_get(&m, "domain"), c);
    case_read_gauges(r, rmap_get(&m, "trackers"), rmap_get(&m, "control_volumes"), c);
    read_output(r, rmap_get(&m, "output"), c);
    read_check(r, rmap_get(&m, "check"), c);
}

/* The message of a parser that failed: file, line and column of the problem, and what to do. The
 * reader's errors (a byte that is not UTF-8 text, a control character) carry a byte offset instead
 * of a mark: their line is counted here (libyaml reports line 1 for them). A tab in the
 * indentation of the line gets its own hint (YAML forbids tabs there). */
static void yaml_syntax_error(const char *path, const yaml_parser_t *p, const char *data, size_t size, char *err,
                              size_t errlen)
{
    const char *problem = p->problem ? p->problem : "unknown problem";
    if (p->error == YAML_READER_ERROR) {
        size_t off = p->problem_offset < size ? p->problem_offset : size, line_start = 0;
        int line = 1;
        for (size_t i = 0; i < off; i++)
            if (data[i] == '\n')
                line++, line_start = i + 1;
        const int control = strstr(problem, "control") != NULL;
        char byte[32] = "";
        if (control)
            snprintf(byte, sizeof byte, "byte 0x%02x, ", (unsigned)p->problem_value & 0xffu);
        snprintf(err, errlen, "%s:%d: the file is not UTF-8 text: %s (%scolumn %d); %s", path, line, problem, byte,
                 (int)(off - line_start) + 1,
                 control ? "remove the control character" : "save the file as UTF-8 (an accented letter of a Latin-1 "
                 "or Windows-1252 file, even in a comment, is not UTF-8)");
        return;
    }
    const int line = (int)p->problem_mark.line + 1;
    int tab = 0; /* a tab in the indentation of the problem's line */
    size_t i = 0;
    for (int l = 1; l < line && i < size; i++)
        l += data[i] == '\n';
    for (; i < size && (data[i] == ' ' || data[i] == '\t'); i++)
        tab |= data[i] == '\t';
    snprintf(err, errlen, "%s:%d: YAML syntax error: %s%s%s (column %d); %s", path, line, problem,
             p->context ? " " : "", p->context ? p->context : "", (int)p->problem_mark.column + 1,
             tab ? "the line is indented with a tab, which YAML does not allow: indent with spaces"
                 : "fix the YAML syntax");
}

/* A case file is one YAML document: a second one (after a `---` line) would be ignored. 0, or -1
 * with the message. */
static int yaml_second_document(const char *path, yaml_parser_t *p, const char *data, size_t size, char *err,
                                size_t errlen)
{
    yaml_document_t more;
    if (!yaml_parser_load(p, &more)) {
        yaml_syntax_error(path, p, data, size, err, errlen);
        return -1;
    }
    const yaml_node_t *root = yaml_document_get_root_node(&more);
    if (root)
        snprintf(err, errlen, "%s:%d: a second YAML document starts here (after a `---` line); a case file holds one "
                 "case: remove the `---` line and what follows, or put it in a file of its own", path,
                 (int)(more.start_mark.line ? more.start_mark.line : root->start_mark.line) + 1);
    yaml_document_delete(&more);
    return root ? -1 : 0;
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
        yaml_syntax_error(path, &parser, data, size, err, errlen);
        yaml_parser_delete(&parser);
        return LAHAR_EXIT_BAD_INPUT;
    }
    if (yaml_document_get_root_node(&doc) && yaml_second_document(path, &parser, data, size, err, errlen) != 0) {
        yaml_document_delete(&doc);
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
    FILE *fp = lahar_fopen_input(path, "rb");
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

const char *lahar_case_path_abs(const lahar_case *c, char *buf, size_t size)
{
    char *abs = realpath(c->path, NULL);
    snprintf(buf, size, "%s", abs ? abs : c->path);
    free(abs);
    return buf;
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
