/* Every key of the case format, defined once: name, type, whether required, default, allowed range
 * or choices, unit and a one-line description, one table per section. The loader (case.c) takes
 * from it the keys a section accepts, the defaults and the range checks with their messages;
 * `lahar keys [SECTION]` prints it; cases/reference.yaml is generated from it (`lahar keys --yaml`)
 * and a test fails when that file is stale. Checks that tie several keys together stay in the
 * section's reader. */
#ifndef LAHAR_CASE_KEYS_H
#define LAHAR_CASE_KEYS_H
#include <stddef.h>
#include <stdio.h>

typedef enum {
    LAHAR_KEY_NUMBER,  /* a finite number */
    LAHAR_KEY_WHOLE,   /* a whole number (written as a number, checked to be whole) */
    LAHAR_KEY_BOOL,    /* true | false (yes | no) */
    LAHAR_KEY_CHOICE,  /* one name of `choices` */
    LAHAR_KEY_VECTOR,  /* a list of numbers (dimension-long unless the doc says otherwise) */
    LAHAR_KEY_TEXT,    /* a name, a file path or an expression */
    LAHAR_KEY_MAPPING, /* a nested section (its own table) */
    LAHAR_KEY_LIST     /* a list of mappings (its own table) */
} lahar_key_type;

/* Range flags: which bounds apply and whether they are open. */
enum { LAHAR_KEY_LO = 1, LAHAR_KEY_HI = 2, LAHAR_KEY_LO_OPEN = 4, LAHAR_KEY_HI_OPEN = 8 };

typedef struct {
    const char *name;
    lahar_key_type type;
    int required;
    const char *def;            /* the default as users read it ("0.25", "dx/2"); NULL: none */
    int range;                  /* LAHAR_KEY_LO | ... ; 0: any value */
    double lo, hi;
    const char *const *choices; /* LAHAR_KEY_CHOICE (NULL-terminated) */
    const char *unit;           /* "m", "Pa s", ... ; "" for dimensionless */
    const char *doc;            /* one line: what it is (and, after "; ", a hint for range errors) */
    const char *const *only;    /* the variants of the section the key belongs to (bodies[]: the shapes),
                                   NULL-terminated; NULL: every variant */
} lahar_key;
/* 1 when key k belongs to the variant `variant` (always when k->only is NULL). */
int lahar_key_applies(const lahar_key *k, const char *variant);

typedef struct {
    const char *path; /* "sph", "time", "materials.NAME", "sph.blocks[]", ... ("" = the top) */
    const char *doc;
    const lahar_key *keys; /* terminated by {NULL} */
} lahar_key_section;

/* All sections, in the order of the reference. */
const lahar_key_section *lahar_key_sections(int *count);
const lahar_key_section *lahar_key_section_find(const char *path);
const lahar_key *lahar_key_find(const lahar_key_section *s, const char *name);
/* The default as a number; NaN when it is not one (computed defaults such as "dx/2"). */
double lahar_key_default(const lahar_key *k);
/* 1 when v satisfies the key's range (always for keys without one; wholeness for WHOLE keys). */
int lahar_key_in_range(const lahar_key *k, double v);
/* "must be > 0 Pa (got 3)"-style text for v outside the range, with the doc's hint. */
void lahar_key_range_error(const lahar_key *k, double v, char *out, size_t n);
/* `lahar keys [SECTION]`: a table of one section, or of all when section is NULL. SECTION is a
 * table path (bodies[], materials.NAME) or the same without its [] / .NAME. Returns 0, or -1 when
 * the section is unknown (the known ones are printed to stderr). */
int lahar_keys_print(FILE *f, const char *section);
/* cases/reference.yaml: every key with its default, as comments. */
void lahar_keys_print_yaml(FILE *f);

#endif
