/* The case loader's private interface (common/io/case*.c; users include case.h): the reader that
 * carries the YAML document and the first error, the typed accessors that report
 * `file:line: key.path: what; what to do` (case_reader.c), and what one section's reader
 * needs from another's. */
#ifndef LAHAR_CASE_READER_H
#define LAHAR_CASE_READER_H
#include <stddef.h>
#include <stdint.h>
#include <yaml.h>
#include "case.h"
#include "case_keys.h"
#include "terrain.h"

#define KEY_MAX 192

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

/* A mapping being read: its node and the key path prefix for messages ("bodies[3]"). */
typedef struct {
    reader *r;
    yaml_node_t *node;
    char prefix[KEY_MAX];
    const lahar_key_section *sec; /* the section's key table (case_keys.c), once rmap_section ran */
} rmap;

/* case_reader.c */
const char *rd_closest_name(const char *s, const char *const *names);
void rd_join_names(const char *const *names, char *out, size_t n);
void rd_key_join(const char *prefix, const char *key, char out[KEY_MAX]);
double rd_key_num(rmap *m, const char *key);
double rd_key_num_def(rmap *m, const char *key, double def);
double rd_key_num_req(rmap *m, const char *key, int required, double def);
int rd_key_choice(rmap *m, const char *key);
int rd_key_bool(rmap *m, const char *key);
const char *rd_node_kind(const yaml_node_t *n);
int rd_number(reader *r, yaml_node_t *n, const char *key, double *out);
int rd_vec(reader *r, yaml_node_t *n, const char *key, int count, double *out);
void rd_fail(reader *r, const yaml_node_t *n, const char *key, const char *fmt, ...);
yaml_node_t *rd_node(reader *r, int id);
int rmap_bool(rmap *m, const char *key, int def);
void rmap_check_keys(rmap *m, const char *const *known);
int rmap_enum(rmap *m, const char *key, const char *const *names, int required, int def);
void rmap_fail(rmap *m, const char *key, const char *fmt, ...);
yaml_node_t *rmap_get(const rmap *m, const char *key);
void rmap_missing(rmap *m, const char *key, const char *example);
void rmap_name(rmap *m, const char *key, int required, const char *def, char out[LAHAR_NAME_MAX]);
double rmap_num(rmap *m, const char *key, int required, double def, const char *example);
int rmap_open(reader *r, yaml_node_t *n, const char *prefix, rmap *m);
void rmap_section(rmap *m, const char *path);
const char *rmap_str(rmap *m, const char *key, int required, const char *def, const char *example);
int rmap_vec(rmap *m, const char *key, int count, double *out, int required, const char *example);
const char *rd_scalar(const yaml_node_t *n);
yaml_node_t *rd_seq_item(reader *r, const yaml_node_t *n, int i);
int rd_seq_len(const yaml_node_t *n);

/* case_bodies.c */
void case_check_overlaps(reader *r, yaml_node_t *bodies, lahar_case *c);
/* a list of points (each dim numbers) as a new array of 3-vectors (z = 0 in 2D) */
double (*case_read_points(reader *r, yaml_node_t *n, const char *key, int dim, int *np))[3];
void case_read_bodies(reader *r, yaml_node_t *n, lahar_case *c);
void case_read_terrain(reader *r, yaml_node_t *n, lahar_case *c);

/* case_blocks.c */
int case_init_file_read(const char *path, int64_t n, double *out[4], int found[4], char *err, size_t errlen);
void case_read_block(reader *r, yaml_node_t *n, int i, lahar_case *c);

/* case_lattice.c */
void case_check_body_layers(rmap *m, const lahar_case *c);
int case_first_round_body(const lahar_case *c);
void case_check_blocks_placement(reader *r, yaml_node_t *bl, lahar_case *c);

/* case_sph.c */
void case_read_sph(reader *r, yaml_node_t *n, lahar_case *c);

/* case_gauges.c */
void case_read_gauges(reader *r, yaml_node_t *tn, yaml_node_t *vn, lahar_case *c);
void case_read_probes(reader *r, yaml_node_t *n, lahar_case *c);

/* case_flow.c */
void case_read_domain(reader *r, yaml_node_t *n, lahar_case *c);
void case_read_inlets(reader *r, yaml_node_t *n, lahar_case *c);
void case_read_outlets(reader *r, yaml_node_t *n, lahar_case *c);

#endif
