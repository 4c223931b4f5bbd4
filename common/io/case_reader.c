/* The typed accessors of the case loader (case_reader.h). */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>

#include "case_keys.h"
#include "case_reader.h"

/* --- reader: the document, the first error, and the typed accessors ------------------------- */

void rd_fail(reader *r, const yaml_node_t *n, const char *key, const char *fmt, ...)
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

yaml_node_t *rd_node(reader *r, int id) { return yaml_document_get_node(r->doc, id); }

const char *rd_node_kind(const yaml_node_t *n)
{
    switch (n->type) {
    case YAML_SCALAR_NODE: return "a scalar";
    case YAML_SEQUENCE_NODE: return "a list";
    case YAML_MAPPING_NODE: return "a mapping";
    default: return "nothing";
    }
}

const char *rd_scalar(const yaml_node_t *n) { return (const char *)n->data.scalar.value; }

int rd_seq_len(const yaml_node_t *n)
{
    return (int)(n->data.sequence.items.top - n->data.sequence.items.start);
}

yaml_node_t *rd_seq_item(reader *r, const yaml_node_t *n, int i)
{
    return rd_node(r, n->data.sequence.items.start[i]);
}

/* Edit distance for "did you mean" (keys are short). */
static int rd_edit_distance(const char *a, const char *b)
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
const char *rd_closest_name(const char *s, const char *const *names)
{
    const char *best = NULL;
    int bd = 1 << 30;
    for (int i = 0; names[i]; i++) {
        int d = rd_edit_distance(s, names[i]);
        if (d < bd) {
            bd = d;
            best = names[i];
        }
    }
    int len = (int)strlen(s);
    return bd <= (len > 6 ? 3 : 2) ? best : NULL;
}

void rd_join_names(const char *const *names, char *out, size_t n)
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

void rd_key_join(const char *prefix, const char *key, char out[KEY_MAX])
{
    if (prefix[0])
        snprintf(out, KEY_MAX, "%.*s.%s", KEY_MAX / 2, prefix, key);
    else
        snprintf(out, KEY_MAX, "%s", key);
}

int rmap_open(reader *r, yaml_node_t *n, const char *prefix, rmap *m)
{
    m->r = r;
    m->node = n;
    m->sec = NULL;
    snprintf(m->prefix, sizeof m->prefix, "%s", prefix);
    if (r->failed)
        return -1;
    if (!n || n->type != YAML_MAPPING_NODE) {
        rd_fail(r, n, prefix, "expected a mapping of keys to values, got %s; write it as {key: value, ...} "
                "or as indented key: value lines", n ? rd_node_kind(n) : "nothing");
        return -1;
    }
    return 0;
}

yaml_node_t *rmap_get(const rmap *m, const char *key)
{
    if (m->r->failed || !m->node)
        return NULL;
    for (yaml_node_pair_t *p = m->node->data.mapping.pairs.start; p < m->node->data.mapping.pairs.top; p++) {
        yaml_node_t *k = rd_node(m->r, p->key);
        if (k && k->type == YAML_SCALAR_NODE && strcmp(rd_scalar(k), key) == 0)
            return rd_node(m->r, p->value);
    }
    return NULL;
}

/* The sections other than `here` whose table has a key `name` ("time", "sph, probes[]"), in
 * out; 0 when none has. */
static int rd_key_elsewhere(const char *name, const lahar_key_section *here, char *out, size_t n)
{
    int count = 0, found = 0;
    const lahar_key_section *secs = lahar_key_sections(&count);
    size_t k = 0;
    out[0] = '\0';
    for (int i = 0; i < count && k < n; i++) {
        if (&secs[i] == here || !lahar_key_find(&secs[i], name))
            continue;
        if (found == 3) { /* a common name (position, name, rate): a few examples do */
            snprintf(out + k, n - k, ", ...");
            break;
        }
        int w = snprintf(out + k, n - k, "%s%s", found ? ", " : "", secs[i].path[0] ? secs[i].path : "the top level");
        if (w < 0)
            break;
        k += (size_t)w;
        found++;
    }
    return found;
}

/* Report the first key that is not in known[] (with a suggestion) or appears twice. */
void rmap_check_keys(rmap *m, const char *const *known)
{
    reader *r = m->r;
    if (r->failed)
        return;
    for (yaml_node_pair_t *p = m->node->data.mapping.pairs.start; p < m->node->data.mapping.pairs.top; p++) {
        yaml_node_t *k = rd_node(r, p->key);
        char key[KEY_MAX];
        if (!k || k->type != YAML_SCALAR_NODE) {
            rd_fail(r, k, m->prefix, "a key must be a plain name, got %s", k ? rd_node_kind(k) : "nothing");
            return;
        }
        rd_key_join(m->prefix, rd_scalar(k), key);
        int ok = 0;
        for (int i = 0; known[i] && !ok; i++)
            ok = strcmp(known[i], rd_scalar(k)) == 0;
        if (!ok) {
            char list[512], where[160];
            rd_join_names(known, list, sizeof list);
            const char *near = rd_closest_name(rd_scalar(k), known);
            if (rd_key_elsewhere(rd_scalar(k), m->sec, where, sizeof where))
                rd_fail(r, k, key, "unknown key here; '%s' is a key of: %s (move it there; known keys here: %s)",
                        rd_scalar(k), where, list);
            else if (rd_scalar(k)[0] && strspn(rd_scalar(k), "0123456789") == strlen(rd_scalar(k)))
                rd_fail(r, k, key, "unknown key '%s': a number with a decimal comma? In {key: 0,02} the comma "
                        "separates entries; write decimals with a point (0.02)", rd_scalar(k));
            else if (near)
                rd_fail(r, k, key, "unknown key; did you mean '%s'? (known keys here: %s)", near, list);
            else
                rd_fail(r, k, key, "unknown key; known keys here: %s", list);
            return;
        }
        for (yaml_node_pair_t *q = m->node->data.mapping.pairs.start; q < p; q++) {
            yaml_node_t *k2 = rd_node(r, q->key);
            if (k2 && k2->type == YAML_SCALAR_NODE && strcmp(rd_scalar(k2), rd_scalar(k)) == 0) {
                rd_fail(r, k, key, "duplicate key (first given on line %d); keep only one",
                        (int)k2->start_mark.line + 1);
                return;
            }
        }
    }
}

void rmap_missing(rmap *m, const char *key, const char *example)
{
    char full[KEY_MAX];
    rd_key_join(m->prefix, key, full);
    rd_fail(m->r, m->node, full, "missing required key; add e.g. `%s: %s`", key, example);
}

/* Fail on the value of `key` (or on the mapping when the key is absent). */
void rmap_fail(rmap *m, const char *key, const char *fmt, ...)
{
    if (m->r->failed)
        return;
    char full[KEY_MAX], msg[512];
    rd_key_join(m->prefix, key, full);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    yaml_node_t *n = rmap_get(m, key);
    rd_fail(m->r, n ? n : m->node, full, "%s", msg);
}

int rd_number(reader *r, yaml_node_t *n, const char *key, double *out)
{
    if (r->failed)
        return -1;
    if (n->type != YAML_SCALAR_NODE) {
        rd_fail(r, n, key, "expected a number, got %s; write a plain number such as 0.05 or 1e-3", rd_node_kind(n));
        return -1;
    }
    const char *s = rd_scalar(n);
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

double rmap_num(rmap *m, const char *key, int required, double def, const char *example)
{
    yaml_node_t *n = rmap_get(m, key);
    if (!n) {
        if (required && !m->r->failed)
            rmap_missing(m, key, example);
        return def;
    }
    char full[KEY_MAX];
    rd_key_join(m->prefix, key, full);
    double v = def;
    rd_number(m->r, n, full, &v);
    return v;
}

/* A list of exactly n numbers into out (left untouched when absent). Returns 1 if present. */
int rd_vec(reader *r, yaml_node_t *n, const char *key, int count, double *out)
{
    if (r->failed)
        return 0;
    if (n->type != YAML_SEQUENCE_NODE || rd_seq_len(n) != count) {
        if (n->type == YAML_SEQUENCE_NODE)
            rd_fail(r, n, key, "expected a list of %d numbers, got %d%s", count, rd_seq_len(n),
                    count == 2 ? " (2D cases give [x, y])" : (count == 3 ? " (3D cases give [x, y, z])" : ""));
        else
            rd_fail(r, n, key, "expected a list of %d numbers like [%s], got %s", count,
                    count == 2 ? "x, y" : (count == 3 ? "x, y, z" : "a, b, ..."), rd_node_kind(n));
        return 0;
    }
    double tmp[16];
    for (int i = 0; i < count && i < 16; i++) {
        char ik[KEY_MAX];
        snprintf(ik, sizeof ik, "%.*s[%d]", KEY_MAX - 16, key, i);
        if (rd_number(r, rd_seq_item(r, n, i), ik, &tmp[i]) != 0)
            return 0;
    }
    memcpy(out, tmp, (size_t)count * sizeof *out);
    return 1;
}

int rmap_vec(rmap *m, const char *key, int count, double *out, int required, const char *example)
{
    yaml_node_t *n = rmap_get(m, key);
    if (!n) {
        if (required && !m->r->failed)
            rmap_missing(m, key, example);
        return 0;
    }
    char full[KEY_MAX];
    rd_key_join(m->prefix, key, full);
    return rd_vec(m->r, n, full, count, out);
}

const char *rmap_str(rmap *m, const char *key, int required, const char *def, const char *example)
{
    yaml_node_t *n = rmap_get(m, key);
    if (!n) {
        if (required && !m->r->failed)
            rmap_missing(m, key, example);
        return def;
    }
    if (n->type != YAML_SCALAR_NODE || rd_scalar(n)[0] == '\0') {
        rmap_fail(m, key, "expected a non-empty name/text, got %s", n->type == YAML_SCALAR_NODE ? "an empty value" : rd_node_kind(n));
        return def;
    }
    return rd_scalar(n);
}

/* A name shorter than LAHAR_NAME_MAX. */
void rmap_name(rmap *m, const char *key, int required, const char *def, char out[LAHAR_NAME_MAX])
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

int rmap_enum(rmap *m, const char *key, const char *const *names, int required, int def)
{
    const char *s = rmap_str(m, key, required, NULL, names[0]);
    if (!s || m->r->failed)
        return def;
    for (int i = 0; names[i]; i++)
        if (strcmp(s, names[i]) == 0)
            return i;
    char list[256];
    rd_join_names(names, list, sizeof list);
    const char *near = rd_closest_name(s, names);
    if (near)
        rmap_fail(m, key, "unknown value '%s'; did you mean '%s'? (one of: %s)", s, near, list);
    else
        rmap_fail(m, key, "unknown value '%s'; use one of: %s", s, list);
    return def;
}

int rmap_bool(rmap *m, const char *key, int def)
{
    static const char *const names[] = {"false", "true", "no", "yes", NULL};
    const char *s = rmap_str(m, key, 0, NULL, "true");
    if (!s || m->r->failed)
        return def;
    for (int i = 0; names[i]; i++)
        if (strcmp(s, names[i]) == 0)
            return i == 1 || i == 3;
    /* no "did you mean": the nearest name of on / off / True is as likely the opposite */
    rmap_fail(m, key, "expected true or false (or yes / no, in lower case), got '%s'", s);
    return def;
}

/* The keys of this mapping are those of `path`'s table (case_keys.c): report the first unknown or
 * repeated one; key_num and key_whole then take defaults and ranges from the table. */
void rmap_section(rmap *m, const char *path)
{
    m->sec = lahar_key_section_find(path);
    const char *known[64];
    int n = 0;
    for (const lahar_key *k = m->sec ? m->sec->keys : NULL; k && k->name && n < 63; k++)
        known[n++] = k->name;
    known[n] = NULL;
    rmap_check_keys(m, known);
}

/* A number key of the section's table, required or not as the caller says (keys required by one
 * model of a section only), else its default `def` (the table's default when it is a number and
 * def is NaN), checked against the table's range with the table's message. */
double rd_key_num_req(rmap *m, const char *key, int required, double def)
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
    double v = rmap_num(m, key, required, def, example);
    if (m->r->failed || !present)
        return v;
    if (!lahar_key_in_range(k, v)) {
        char msg[512];
        lahar_key_range_error(k, v, msg, sizeof msg);
        rmap_fail(m, key, "%s", msg);
    }
    return v;
}

/* The same, required as the table says. */
double rd_key_num_def(rmap *m, const char *key, double def)
{
    const lahar_key *k = lahar_key_find(m->sec, key);
    return rd_key_num_req(m, key, k ? k->required : 0, def);
}

double rd_key_num(rmap *m, const char *key) { return rd_key_num_def(m, key, NAN); }

/* A choice key of the section's table: the index of its value in the table's choices (which are in
 * the order of the C enum the caller stores), required or defaulted as the table says. */
int rd_key_choice(rmap *m, const char *key)
{
    const lahar_key *k = lahar_key_find(m->sec, key);
    if (!k || !k->choices) {
        rmap_fail(m, key, "internal: no choice entry in the key table (common/io/case_keys.c)");
        return 0;
    }
    int def = 0;
    for (int i = 0; k->def && k->choices[i]; i++)
        if (strcmp(k->choices[i], k->def) == 0)
            def = i;
    return rmap_enum(m, key, k->choices, k->required, def);
}

/* A true/false key of the section's table, defaulted as the table says. */
int rd_key_bool(rmap *m, const char *key)
{
    const lahar_key *k = lahar_key_find(m->sec, key);
    if (!k) {
        rmap_fail(m, key, "internal: no entry in the key table (common/io/case_keys.c)");
        return 0;
    }
    return rmap_bool(m, key, k->def && strcmp(k->def, "true") == 0);
}
