/* Writes the message seeds of the fuzz corpus (tests/fuzz/corpus/msg, tests/fuzz/corpus/link):
 * representative messages of a run encoded with the lcm-gen encoders and lahar's own code (the
 * scene of real cases, LOADS with contact points, BODY_STATE, STATUS with and without an
 * instability report, HELLO, STEP, STOP, NACK, heartbeats), and the frames a link publishes for
 * them, plain and authenticated, in the input format of fuzz_link.c; and the scene reproducers of
 * OUT_DIR/../regressions/msg for the current scene_t.
 *   make_seeds CASES_DIR OUT_DIR      (writes the files of OUT_DIR/msg and OUT_DIR/link)
 *   make_seeds --compare FRESH_DIR COMMITTED_DIR          (the same files, equal as below)
 *   make_seeds --compare-written FRESH_DIR COMMITTED_DIR  (FRESH_DIR's files only)
 * The comparisons exit 1 naming the first file and byte that differ. */
#include <dirent.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "case.h"
#include "fuzz.h"
#include "instability.h"
#include "lahar_heartbeat_t.h"
#include "lahar_hello_t.h"
#include "lahar_nack_t.h"
#include "lahar_status_t.h"
#include "lahar_step_t.h"
#include "lahar_stop_t.h"
#include "link.h"
#include "scene_msg.h"

#define RUN_ID 0x1a2b3c4d5e6fLL /* as fuzz_link.c */

typedef struct {
    uint8_t *data;
    size_t n, cap;
} bytes;

static void put(bytes *b, const void *p, size_t n)
{
    if (b->n + n > b->cap) {
        b->cap = 2 * (b->n + n);
        b->data = realloc(b->data, b->cap);
        if (!b->data) {
            fprintf(stderr, "make_seeds: out of memory\n");
            exit(1);
        }
    }
    memcpy(b->data + b->n, p, n);
    b->n += n;
}

static const char *out_dir;

static void write_file(const char *sub, const char *name, const void *p, size_t n)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s/%s", out_dir, sub, name);
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(p, 1, n, f) != n || fclose(f) != 0) {
        fprintf(stderr, "make_seeds: cannot write %s\n", path);
        exit(1);
    }
}

/* a msg seed: the type byte, then the encoding */
static void write_msg(const char *name, int type, const void *p, int n)
{
    bytes b = {0};
    uint8_t t = (uint8_t)type;
    put(&b, &t, 1);
    put(&b, p, (size_t)n);
    write_file("msg", name, b.data, b.n);
    free(b.data);
}

/* ---- capturing transport: the frames a link publishes become datagram records ---- */
typedef struct {
    bytes *rec;
} capture;
static void *cap_open(const char *u, char *e, size_t n) { (void)u; (void)e; (void)n; return NULL; }
static int cap_publish(void *impl, const char *ch, const void *data, size_t size)
{
    (void)ch;
    capture *c = impl;
    uint8_t hdr[3] = {0x00, (uint8_t)(size & 0xff), (uint8_t)(size >> 8)};
    if (c->rec && size < 65536) {
        put(c->rec, hdr, 3);
        put(c->rec, data, size);
    }
    return 0;
}
static int cap_subscribe(void *impl, const char *r, int q, lahar_transport_recv_fn fn, void *u)
{
    (void)impl; (void)r; (void)q; (void)fn; (void)u;
    return 0;
}
static int cap_handle(void *impl, int ms) { (void)impl; (void)ms; return 0; }
static void cap_close(void *impl) { (void)impl; }
static const lahar_transport_ops cap_ops = {"capture://", cap_open, cap_publish, cap_subscribe, cap_handle, cap_close};

typedef struct {
    capture cap;
    lahar_transport t;
    lahar_link *l;
} sender;

static void sender_open(sender *s, int role, int auth, bytes *rec)
{
    char err[256];
    s->cap.rec = rec;
    s->t.ops = &cap_ops;
    s->t.impl = &s->cap;
    s->l = lahar_link_create(&s->t, role, RUN_ID, 0, err, sizeof err);
    if (!s->l) {
        fprintf(stderr, "make_seeds: %s\n", err);
        exit(1);
    }
    if (auth)
        lahar_link_set_auth_key(s->l, fuzz_auth_key);
}

/* the encodings of one run's messages */
typedef struct {
    bytes m[LAHAR_NMSG];
} encodings;

#define ENCODE(T, msgp, out)                                                                       \
    do {                                                                                           \
        int n_ = T##_encoded_size(msgp);                                                           \
        uint8_t *b_ = malloc((size_t)n_);                                                          \
        if (!b_ || T##_encode(b_, 0, n_, (msgp)) != n_) {                                          \
            fprintf(stderr, "make_seeds: cannot encode " #T "\n");                                 \
            exit(1);                                                                               \
        }                                                                                          \
        (out)->n = 0;                                                                              \
        put((out), b_, (size_t)n_);                                                                \
        free(b_);                                                                                  \
    } while (0)

/* The scene of cases/<name>, changed by mutate (NULL: as it is) before it is encoded. */
static void encode_scene(const char *cases, const char *name, void (*mutate)(lahar_scene_t *), bytes *out)
{
    char path[4096], err[2048];
    snprintf(path, sizeof path, "%s/%s", cases, name);
    lahar_case c;
    if (lahar_case_load_err(path, &c, err, sizeof err) != 0) {
        fprintf(stderr, "make_seeds: %s\n", err);
        exit(1);
    }
    lahar_scene_t m;
    if (lahar_scene_msg_from_case(&c, "/tmp/lahar-out", c.nbody > 0, c.nblock > 0, RUN_ID, &m) != 0) {
        fprintf(stderr, "make_seeds: scene of %s\n", name);
        exit(1);
    }
    m.case_path = (char *)name; /* no absolute path of the machine in the seeds */
    if (mutate)
        mutate(&m);
    ENCODE(lahar_scene_t, &m, out);
    lahar_scene_msg_release(&m);
    lahar_case_free(&c);
}

static void encode_loads(int nbody, int npoints_each, bytes *out)
{
    int np = nbody * npoints_each;
    lahar_loads_t m = {.run_id = RUN_ID, .step = 3, .nbody = nbody, .ntotal = np,
                       .reach_lo = {-1, -1, -1}, .reach_hi = {2, 2, 2}};
    double(*rows)[3] = calloc((size_t)(2 * nbody + 2 * np + 1), sizeof *rows);
    m.body_id = calloc((size_t)nbody + 1, sizeof *m.body_id);
    m.npoints = calloc((size_t)nbody + 1, sizeof *m.npoints);
    m.force = calloc((size_t)nbody + 1, sizeof *m.force);
    m.torque = calloc((size_t)nbody + 1, sizeof *m.torque);
    m.point_x = calloc((size_t)np + 1, sizeof *m.point_x);
    m.point_f = calloc((size_t)np + 1, sizeof *m.point_f);
    for (int i = 0; i < 2 * nbody + 2 * np; i++)
        for (int a = 0; a < 3; a++)
            rows[i][a] = 0.25 * i + a;
    for (int i = 0; i < nbody; i++) {
        m.body_id[i] = i;
        m.npoints[i] = npoints_each;
        m.force[i] = rows[i];
        m.torque[i] = rows[nbody + i];
    }
    for (int i = 0; i < np; i++) {
        m.point_x[i] = rows[2 * nbody + i];
        m.point_f[i] = rows[2 * nbody + np + i];
    }
    ENCODE(lahar_loads_t, &m, out);
    free(rows);
    free(m.body_id); free(m.npoints); free(m.force); free(m.torque); free(m.point_x); free(m.point_f);
}

static void encode_body_state(int n, bytes *out)
{
    double rows[8][4] = {{0}};
    double *x[8], *q[8], *v[8], *w[8];
    int32_t id[8];
    for (int i = 0; i < n && i < 8; i++) {
        id[i] = i + 1;
        rows[i][0] = 1.0;
        rows[i][1] = 0.5 * i;
        x[i] = q[i] = v[i] = w[i] = rows[i];
    }
    lahar_body_state_t m = {.run_id = RUN_ID, .step = 3, .t = 0.015, .n = n, .id = id, .x = x, .q = q, .v = v, .w = w};
    ENCODE(lahar_body_state_t, &m, out);
}

static void encode_status(const char *message, int error, bytes *out)
{
    lahar_status_t s;
    memset(&s, 0, sizeof s);
    s.run_id = RUN_ID;
    s.step = 3;
    s.role = LAHAR_ROLE_SPH;
    s.dt_proposed = 1e-4;
    s.error = error;
    snprintf((char *)s.message, sizeof s.message, "%s", message);
    ENCODE(lahar_status_t, &s, out);
}

static void all_encodings(const char *cases, encodings *e)
{
    memset(e, 0, sizeof *e);
    static const char *caps[] = {"dim2", "dim3", "hertz", "subcycle"};
    lahar_hello_t h = {.run_id = RUN_ID, .step = -1, .role = 0, .engine = "lahar", .version = "0.1.0",
                       .protocol_version = 1, .ncapabilities = 4, .capabilities = (char **)caps, .host = "host", .pid = 42};
    ENCODE(lahar_hello_t, &h, &e->m[LAHAR_FRAME_T_MSG_HELLO]);
    encode_scene(cases, "debris_2d.yaml", NULL, &e->m[LAHAR_FRAME_T_MSG_SCENE]);
    lahar_step_t st = {.run_id = RUN_ID, .step = 3, .t = 0.01, .dt = 0.005, .t_next = 0.015, .write_output = 1};
    ENCODE(lahar_step_t, &st, &e->m[LAHAR_FRAME_T_MSG_STEP]);
    lahar_instability u = {.what = "density out of band", .kind = "particle", .id = 17, .name = "",
                           .x = {0.1, 0.2, 0.0}, .step = 3, .t = 0.015, .value = 1.9, .limit = 1.5,
                           .text = "particle 17 has density 1.9 rho0 at (0.1, 0.2, 0) m in step 3"};
    char text[512];
    lahar_instability_encode(&u, text, sizeof text);
    encode_status(text, 1, &e->m[LAHAR_FRAME_T_MSG_STATUS]);
    encode_body_state(3, &e->m[LAHAR_FRAME_T_MSG_BODY_STATE]);
    encode_loads(3, 4, &e->m[LAHAR_FRAME_T_MSG_LOADS]);
    lahar_stop_t sp = {.run_id = RUN_ID, .step = 3, .reason = 1, .message = "the SPH node reports at step 3"};
    ENCODE(lahar_stop_t, &sp, &e->m[LAHAR_FRAME_T_MSG_STOP]);
    lahar_heartbeat_t hb = {.run_id = RUN_ID, .step = 2, .role = 0};
    ENCODE(lahar_heartbeat_t, &hb, &e->m[LAHAR_FRAME_T_MSG_HEARTBEAT]);
    int32_t missing[2] = {0, 1};
    lahar_nack_t nk = {.run_id = RUN_ID, .step = 1, .requester = 0, .target = 2, .channel = "LAHAR_STATUS",
                       .type = LAHAR_FRAME_T_MSG_STATUS, .nmissing = 2, .missing = missing};
    ENCODE(lahar_nack_t, &nk, &e->m[LAHAR_FRAME_T_MSG_NACK]);
}

static int sender_role(int type)
{
    switch (type) {
    case LAHAR_FRAME_T_MSG_STATUS:
    case LAHAR_FRAME_T_MSG_LOADS: return LAHAR_ROLE_SPH;
    case LAHAR_FRAME_T_MSG_BODY_STATE: return LAHAR_ROLE_DEM;
    default: return LAHAR_ROLE_COORDINATOR;
    }
}

/* A link seed: the receiver `role` hears every message of e from its sender (the receiver's own
 * role's messages come from the coordinator instead), then takes each. */
static void write_link(const char *name, const encodings *e, int role, int auth, int known_run, int twice)
{
    bytes rec = {0};
    uint8_t cfg = (uint8_t)(role | (auth ? 4 : 0) | (known_run ? 8 : 0));
    put(&rec, &cfg, 1);
    sender s[LAHAR_NROLES];
    for (int r = 0; r < LAHAR_NROLES; r++)
        sender_open(&s[r], r, auth, &rec);
    for (int rep = 0; rep <= twice; rep++)
        for (int ty = 1; ty < LAHAR_NMSG; ty++) {
            int from = sender_role(ty);
            if (from == role)
                from = LAHAR_ROLE_COORDINATOR;
            if (from == role)
                continue;
            lahar_link_send(s[from].l, ty, ty == LAHAR_FRAME_T_MSG_HELLO || ty == LAHAR_FRAME_T_MSG_SCENE ? -1 : 3,
                            e->m[ty].data, (int)e->m[ty].n);
            /* the take op of fuzz_link.c: sender op % 3, type (op >> 2) % 10 */
            for (unsigned op = 0xc0; op <= 0xff; op++)
                if ((op >> 2) % 10 == (unsigned)ty && op % 3 == (unsigned)from) {
                    uint8_t take = (uint8_t)op;
                    put(&rec, &take, 1);
                    break;
                }
        }
    for (int r = 0; r < LAHAR_NROLES; r++)
        lahar_link_destroy(s[r].l);
    write_file("link", name, rec.data, rec.n);
    free(rec.data);
}

/* Mutations of a scene that lahar_scene_msg_to_case must refuse (each crashed a node before
 * the index checks): an edge to vertex nv of the first body with edges, a face vertex -1. */
static void edge_beyond_nv(lahar_scene_t *m)
{
    for (int i = 0; i < m->nbody; i++)
        if (m->bodies[i].ne > 0) {
            m->bodies[i].e[0][1] = m->bodies[i].nv;
            return;
        }
}

static void face_vertex_negative(lahar_scene_t *m)
{
    for (int i = 0; i < m->nbody; i++)
        if (m->bodies[i].nfv > 0) {
            m->bodies[i].face_v[0] = -1;
            return;
        }
}

/* 1 when the encoding decodes as a scene_t (its type hash is the current one) and the scene is
 * refused, 0 when it does not decode, -1 when it is accepted. */
static int scene_refused(const bytes *b)
{
    lahar_scene_t sm;
    if (lahar_scene_t_decode(b->data, 0, (int)b->n, &sm) < 0)
        return 0;
    lahar_case c;
    char err[512];
    int rc = lahar_scene_msg_to_case(&sm, &c, err, sizeof err) == 0 ? -1 : 1;
    if (rc < 0)
        lahar_case_free(&c);
    lahar_scene_t_decode_cleanup(&sm);
    return rc;
}

/* The scene reproducers of regressions/msg (the directory beside OUT_DIR), encoded for the
 * current scene_t: an encoding of an older scene_t fails at the type hash and no longer reaches
 * the checks it once crashed, so they are rewritten whenever the seeds are. `valid` holds the
 * encoding of dem_drop_3d.yaml's scene (a box, edges and faces); the truncated one is cut in its
 * bodies. */
static void write_scene_regressions(const char *cases, const char *corpus, const bytes *valid)
{
    char dir[4096];
    snprintf(dir, sizeof dir, "%s/../regressions", corpus);
    const char *saved = out_dir;
    out_dir = dir;
    static const struct {
        const char *name;
        void (*mutate)(lahar_scene_t *);
    } bad[] = {{"scene_edge_index_beyond_nv", edge_beyond_nv}, {"scene_face_vertex_negative", face_vertex_negative}};
    if (scene_refused(valid) != -1) {
        fprintf(stderr, "make_seeds: the scene of dem_drop_3d.yaml is not accepted as it is\n");
        exit(1);
    }
    bytes b = {0};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        encode_scene(cases, "dem_drop_3d.yaml", bad[k].mutate, &b);
        if (scene_refused(&b) != 1) {
            fprintf(stderr, "make_seeds: %s does not decode, or decodes into a scene that is accepted\n", bad[k].name);
            exit(1);
        }
        write_msg(bad[k].name, LAHAR_FRAME_T_MSG_SCENE, b.data, (int)b.n);
    }
    free(b.data);
    write_msg("scene_truncated", LAHAR_FRAME_T_MSG_SCENE, valid->data, (int)(valid->n * 2 / 3));
    out_dir = saved;
}

/* ---- comparing written seeds with committed ones ----
 * The scenes carry quaternions from the cases' axis-angle orientations, computed with the C
 * library's sin and cos; glibc picks an FMA variant of them on CPUs that have FMA, and the last
 * bits differ between machines. Two files are equal when they have the same length and every
 * byte that differs lies in an 8-byte window holding, in both, finite doubles of the same sign
 * within SEED_MAX_ULP units in the last place (LCM encodes doubles big-endian). What the check
 * is for, a message type changed without rewriting the seeds, changes the 8-byte type hash at
 * the start of every encoding and the lengths, which no such window explains. */
#define SEED_MAX_ULP 16

static int be_doubles_close(const uint8_t *a, const uint8_t *b)
{
    uint64_t ua = 0, ub = 0;
    for (int k = 0; k < 8; k++) {
        ua = ua << 8 | a[k];
        ub = ub << 8 | b[k];
    }
    double da, db;
    memcpy(&da, &ua, 8);
    memcpy(&db, &ub, 8);
    if (!isfinite(da) || !isfinite(db) || signbit(da) != signbit(db))
        return 0;
    uint64_t ma = ua & ~(1ull << 63), mb = ub & ~(1ull << 63); /* magnitudes order as integers */
    return (ma > mb ? ma - mb : mb - ma) <= SEED_MAX_ULP;
}

/* -1 when equal as above, else the offset of the first byte no window explains */
static long first_unexplained_byte(const uint8_t *a, const uint8_t *b, size_t n)
{
    size_t i = 0;
    while (i < n) {
        if (a[i] == b[i]) {
            i++;
            continue;
        }
        size_t q = i >= 7 ? i - 7 : 0, found = SIZE_MAX;
        for (; q <= i && q + 8 <= n; q++)
            if (be_doubles_close(a + q, b + q)) {
                found = q;
                break;
            }
        if (found == SIZE_MAX)
            return (long)i;
        i = found + 8;
    }
    return -1;
}

/* Every file of `from` against the file of that name in `to`: equal as above (compare_bytes), or
 * only there. 0, or 1 after naming each one that fails. */
static int compare_files_of(const char *from, const char *to, int compare_bytes)
{
    DIR *d = opendir(from);
    if (!d) {
        fprintf(stderr, "make_seeds: cannot read the directory %s\n", from);
        return 1;
    }
    int bad = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        char pa[4096], pb[4096];
        snprintf(pa, sizeof pa, "%s/%s", from, e->d_name);
        snprintf(pb, sizeof pb, "%s/%s", to, e->d_name);
        if (!compare_bytes) {
            if (access(pb, R_OK) != 0) {
                fprintf(stderr, "make_seeds: %s has no counterpart %s\n", pa, pb);
                bad = 1;
            }
            continue;
        }
        size_t na = 0, nb = 0;
        uint8_t *a = fuzz_read_file(pa, &na), *b = fuzz_read_file(pb, &nb);
        long at = -1;
        if (!a || !b) {
            fprintf(stderr, "make_seeds: cannot read %s\n", !a ? pa : pb);
            bad = 1;
        } else if (na != nb) {
            fprintf(stderr, "make_seeds: %s (%zu bytes) and %s (%zu bytes) differ in length\n", pa, na, pb, nb);
            bad = 1;
        } else if ((at = first_unexplained_byte(a, b, na)) >= 0) {
            fprintf(stderr, "make_seeds: %s and %s differ at byte %ld (0x%02x, 0x%02x), not by round-off in a double\n",
                    pa, pb, at, a[at], b[at]);
            bad = 1;
        }
        free(a);
        free(b);
    }
    closedir(d);
    return bad;
}

static int compare_main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: make_seeds %s FRESH_DIR COMMITTED_DIR\n", argv[1]);
        return 2;
    }
    int bad = compare_files_of(argv[2], argv[3], 1);
    if (strcmp(argv[1], "--compare") == 0)
        bad |= compare_files_of(argv[3], argv[2], 0); /* nothing committed that is no longer written */
    if (bad)
        fprintf(stderr, "make_seeds: the committed seeds are not what make_seeds writes now: rerun "
                        "build/bin/fuzz_make_seeds cases tests/fuzz/corpus and commit them\n");
    return bad;
}

int main(int argc, char **argv)
{
    if (argc > 1 && (strcmp(argv[1], "--compare") == 0 || strcmp(argv[1], "--compare-written") == 0))
        return compare_main(argc, argv);
    if (argc != 3) {
        fprintf(stderr, "usage: make_seeds CASES_DIR OUT_DIR | --compare FRESH_DIR COMMITTED_DIR | --compare-written FRESH_DIR COMMITTED_DIR\n");
        return 2;
    }
    out_dir = argv[2];
    encodings e;
    all_encodings(argv[1], &e);
    static const char *names[LAHAR_NMSG] = {"", "hello", "scene_debris_2d", "step", "status_unstable", "body_state",
                                             "loads", "stop", "heartbeat", "nack"};
    for (int ty = 1; ty < LAHAR_NMSG; ty++)
        write_msg(names[ty], ty, e.m[ty].data, (int)e.m[ty].n);
    bytes b = {0};
    encode_scene(argv[1], "dem_drop_3d.yaml", NULL, &b);
    write_msg("scene_dem_drop_3d", LAHAR_FRAME_T_MSG_SCENE, b.data, (int)b.n);
    write_scene_regressions(argv[1], argv[2], &b);
    encode_scene(argv[1], "soil_geostatic_3d.yaml", NULL, &b);
    write_msg("scene_soil_geostatic_3d", LAHAR_FRAME_T_MSG_SCENE, b.data, (int)b.n);
    encode_status("", 0, &b);
    write_msg("status_ok", LAHAR_FRAME_T_MSG_STATUS, b.data, (int)b.n);
    encode_loads(0, 0, &b);
    write_msg("loads_empty", LAHAR_FRAME_T_MSG_LOADS, b.data, (int)b.n);
    free(b.data);

    write_link("sph_node_plain", &e, LAHAR_ROLE_SPH, 0, 1, 0);
    write_link("dem_node_auth", &e, LAHAR_ROLE_DEM, 1, 1, 1);
    write_link("coordinator_plain", &e, LAHAR_ROLE_COORDINATOR, 0, 1, 0);
    write_link("node_adopts_run", &e, LAHAR_ROLE_DEM, 0, 0, 0);
    /* a LOADS of three frames (more than LAHAR_FRAME_PAYLOAD bytes) */
    encodings big = e;
    memset(&big.m[LAHAR_FRAME_T_MSG_LOADS], 0, sizeof big.m[0]);
    encode_loads(4, 700, &big.m[LAHAR_FRAME_T_MSG_LOADS]);
    write_link("dem_node_multiframe", &big, LAHAR_ROLE_DEM, 0, 1, 0);
    free(big.m[LAHAR_FRAME_T_MSG_LOADS].data);
    for (int ty = 0; ty < LAHAR_NMSG; ty++)
        free(e.m[ty].data);
    printf("make_seeds: wrote %s/msg and %s/link\n", out_dir, out_dir);
    return 0;
}
