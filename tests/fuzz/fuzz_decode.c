/* The receiving end of every message type, shared by fuzz_msg.c and fuzz_link.c. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "case.h"
#include "fuzz.h"
#include "instability.h"
#include "lahar_hello_t.h"
#include "lahar_nack_t.h"
#include "lahar_status_t.h"
#include "lahar_step_t.h"
#include "lahar_stop_t.h"
#include "link.h"
#include "msg_check.h"
#include "scene_msg.h"

const uint8_t fuzz_auth_key[32] = {0x6c, 0x61, 0x68, 0x61, 0x72, 0x2d, 0x66, 0x75, 0x7a, 0x7a, 0x2d, 0x6b, 0x65, 0x79, 0x00, 0x01,
                                   0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08, 0x09, 0x0a, 0x0b, 0x0c, 0x0d, 0x0e, 0x0f, 0x10, 0x11};

void fuzz_fail(const char *file, int line, const char *what)
{
    fprintf(stderr, "%s:%d: fuzz contract violated: %s\n", file, line, what);
    abort();
}

/* Read every vertex an engine reaches through the scene's indices (ASan sees a stray one). */
static double fuzz_touch_case(const lahar_case *c)
{
    double s = 0.0;
    for (int i = 0; i < c->nbody; i++) {
        const lahar_body *b = &c->bodies[i];
        const lahar_shape *sh = &b->shape;
        FUZZ_ASSERT(b->material >= 0 && b->material < c->nmaterial);
        for (int k = 0; k < sh->ne; k++)
            s += sh->v[sh->e[k][0]][0] + sh->v[sh->e[k][1]][1];
        for (int f = 0; f < sh->nf; f++)
            for (int k = sh->face_start[f]; k < sh->face_start[f + 1]; k++)
                s += sh->v[sh->face_v[k]][2];
    }
    for (int i = 0; i < c->nblock; i++) {
        const lahar_particle_block *pb = &c->blocks[i];
        for (int t = 0; t < pb->ntri; t++)
            for (int k = 0; k < 3; k++)
                s += pb->vert[pb->tri[t][k]][k];
        FUZZ_ASSERT(pb->phase == 0 || (pb->material >= 0 && pb->material < c->nmaterial));
    }
    for (int i = 0; i < c->nprobe; i++)
        FUZZ_ASSERT(c->probes[i].body >= -1 && c->probes[i].body < c->nbody);
    return s;
}

static volatile double fuzz_sink;

void fuzz_decode_message(int type, const uint8_t *data, int size)
{
    switch (type) {
    case LAHAR_FRAME_T_MSG_HELLO: {
        lahar_hello_t h;
        if (LAHAR_MSG_DECODE(lahar_hello_t, data, size, &h) >= 0) {
            size_t n = strlen(h.engine) + strlen(h.version) + strlen(h.host);
            for (int i = 0; i < h.ncapabilities; i++)
                n += strlen(h.capabilities[i]);
            fuzz_sink = (double)n;
            lahar_hello_t_decode_cleanup(&h);
        }
        break;
    }
    case LAHAR_FRAME_T_MSG_SCENE: {
        lahar_scene_t sm;
        if (LAHAR_MSG_DECODE(lahar_scene_t, data, size, &sm) < 0)
            break;
        lahar_case c;
        char err[512];
        if (lahar_scene_msg_to_case(&sm, &c, err, sizeof err) == 0) {
            fuzz_sink = fuzz_touch_case(&c) + (double)strlen(sm.output_dir);
            lahar_case_free(&c);
        } else {
            FUZZ_ASSERT(err[0] != '\0');
        }
        lahar_scene_t_decode_cleanup(&sm);
        break;
    }
    case LAHAR_FRAME_T_MSG_STEP: {
        lahar_step_t st;
        if (LAHAR_MSG_DECODE(lahar_step_t, data, size, &st) >= 0)
            lahar_step_t_decode_cleanup(&st);
        break;
    }
    case LAHAR_FRAME_T_MSG_STATUS: {
        /* as the coordinator reads it (coordinator/run/nodes.c, coord_take_status): the text cut to its 512 bytes */
        lahar_status_t s;
        if (LAHAR_MSG_DECODE(lahar_status_t, data, size, &s) < 0)
            break;
        s.message[sizeof s.message - 1] = 0;
        lahar_instability u;
        if (lahar_instability_decode((const char *)s.message, &u)) {
            FUZZ_ASSERT(memchr(u.text, 0, sizeof u.text) && memchr(u.name, 0, sizeof u.name) &&
                        memchr(u.what, 0, sizeof u.what) && memchr(u.kind, 0, sizeof u.kind));
            /* what the coordinator writes back: a report re-encoded fits and decodes again */
            char again[512];
            lahar_instability v;
            lahar_instability_encode(&u, again, sizeof again);
            FUZZ_ASSERT(lahar_instability_decode(again, &v) == 1);
        }
        lahar_status_t_decode_cleanup(&s);
        break;
    }
    case LAHAR_FRAME_T_MSG_BODY_STATE: {
        lahar_body_state_buf b = {0};
        if (lahar_body_state_decode(data, size, &b) == 0) {
            FUZZ_ASSERT(b.n >= 0 && b.n <= b.cap);
            double s = 0.0;
            for (int i = 0; i < b.n; i++)
                s += b.id[i] + b.x[i][0] + b.q[i][3] + b.v[i][2] + b.w[i][1];
            fuzz_sink = s;
        }
        /* a kept buffer decoding a second message, as in the step loop */
        if (size > 1)
            lahar_body_state_decode(data, size - 1, &b);
        lahar_body_state_buf_free(&b);
        break;
    }
    case LAHAR_FRAME_T_MSG_LOADS: {
        lahar_loads_buf b = {0};
        if (lahar_loads_decode(data, size, &b) == 0) {
            FUZZ_ASSERT(b.nbody >= 0 && b.nbody <= b.cap_body && b.ntotal >= 0 && b.ntotal <= b.cap_points);
            /* the points of body i as the contact writer (common/io/output_contacts.c) finds them */
            int64_t off = 0;
            double s = 0.0;
            for (int i = 0; i < b.nbody; i++) {
                s += b.body_id[i] + b.force[i][0] + b.torque[i][2];
                for (int k = 0; k < b.npoints[i]; k++)
                    s += b.point_x[off + k][0] + b.point_f[off + k][2];
                off += b.npoints[i];
            }
            fuzz_sink = s;
        }
        if (size > 1)
            lahar_loads_decode(data, size - 1, &b);
        lahar_loads_buf_free(&b);
        break;
    }
    case LAHAR_FRAME_T_MSG_STOP: {
        lahar_stop_t st;
        if (LAHAR_MSG_DECODE(lahar_stop_t, data, size, &st) >= 0) {
            fuzz_sink = (double)strlen(st.message);
            lahar_stop_t_decode_cleanup(&st);
        }
        break;
    }
    case LAHAR_FRAME_T_MSG_NACK: {
        lahar_nack_t n;
        if (LAHAR_MSG_DECODE(lahar_nack_t, data, size, &n) >= 0) {
            fuzz_sink = (double)strlen(n.channel) + (n.nmissing > 0 ? n.missing[n.nmissing - 1] : 0);
            lahar_nack_t_decode_cleanup(&n);
        }
        break;
    }
    default:
        break;
    }
}
