/* The scene as a message: lahar_case (scene.h) <-> lahar_scene_t (lcm_types/scene_t.lcm). The
 * coordinator sends what it loaded; each node rebuilds the same lahar_case from it, so engines
 * and output writers see exactly the coordinator's numbers (doubles travel bit for bit). */
#ifndef LAHAR_SCENE_MSG_H
#define LAHAR_SCENE_MSG_H
#include <stddef.h>
#include "scene.h"
#include "lahar_scene_t.h"

/* Fill m from c. Strings and numeric rows point into c (keep c alive while m is used); the
 * small pointer tables LCM needs are allocated. Release with lahar_scene_msg_release. */
int lahar_scene_msg_from_case(const lahar_case *c, const char *output_dir, int has_dem, int has_sph,
                              int64_t run_id, lahar_scene_t *m);
void lahar_scene_msg_release(lahar_scene_t *m);

/* Build a case from a decoded scene (deep copy); release with lahar_case_free (common/io/case.h).
 * Returns 0, or -1 with a message in err (malformed scene). */
int lahar_scene_msg_to_case(const lahar_scene_t *m, lahar_case *c, char *err, size_t errlen);

#endif

/* The open boundaries (common/scene_msg_inflow.c; used by the two functions above): fill / release
 * m's inlets, outlets and domain, and read them into c (-1 with a message; c is freed by the
 * caller). */
int lahar_scene_msg_inflow_from_case(const lahar_case *c, lahar_scene_t *m);
void lahar_scene_msg_inflow_release(lahar_scene_t *m);
int lahar_scene_msg_inflow_to_case(const lahar_scene_t *m, lahar_case *c, char *err, size_t errlen);

/* ---- how a node joins a run (shared by lahar-dem and lahar-sph) ---------------------------- */
#include "link.h"

typedef struct {
    lahar_case scene;          /* release with lahar_case_free */
    char output_dir[1024];
    int has_dem, has_sph;
} lahar_node_scene;

/* Wait up to wait_s for the coordinator's HELLO, answer with this node's hello_t (role, engine,
 * version, capabilities), start the 0.25 s heartbeat, watch the coordinator (silent 5 s: lost)
 * and receive the scene. Returns LAHAR_LINK_OK with *out filled, LAHAR_LINK_STOP if the run was
 * stopped, or another LAHAR_LINK_* code with a message in err. */
int lahar_node_join(lahar_link *l, int role, const char *engine, const char *version, const char *const *caps,
                    int ncaps, double wait_s, lahar_node_scene *out, char *err, size_t errlen);

/* Send status_t for step k (fills run_id, step, role and the message, truncated to fit). 0 or -1. */
#include "lahar_status_t.h"
int lahar_node_send_status(lahar_link *l, int role, int64_t step, lahar_status_t *st, const char *message);

#define LAHAR_NODE_COORDINATOR_SILENCE 5.0  /* s: a node gives up on a silent coordinator */
#define LAHAR_HEARTBEAT_PERIOD 0.25         /* s */

/* ---- per-step messages decoded into reusable buffers ------------------------------------------
 * The generated lahar_*_decode allocate every variable-length array on every call; these decode
 * the same LCM encoding (field by field with LCM's primitives, checking the type's fingerprint)
 * into arrays kept between steps, grown by doubling only when a message is larger than any
 * before. Return 0, or -1 on a malformed message or out of memory. */
#include "lahar_body_state_t.h"
#include "lahar_loads_t.h"

typedef struct {
    int64_t run_id, step;
    double t;
    int32_t n, cap;
    int32_t *id;
    double (*x)[3], (*q)[4], (*v)[3], (*w)[3];
} lahar_body_state_buf;
int lahar_body_state_decode(const void *data, int size, lahar_body_state_buf *b);
void lahar_body_state_buf_free(lahar_body_state_buf *b);

typedef struct {
    int64_t run_id, step;
    int32_t nbody, cap_body, ntotal, cap_points;
    int32_t *body_id, *npoints;
    double (*force)[3], (*torque)[3];
    double (*point_x)[3], (*point_f)[3];
    double reach_lo[3], reach_hi[3];
} lahar_loads_buf;
int lahar_loads_decode(const void *data, int size, lahar_loads_buf *b);
void lahar_loads_buf_free(lahar_loads_buf *b);
