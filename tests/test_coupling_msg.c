/* The allocation-free decoders of the per-step messages (common/protocol/scene_msg.c) against LCM's
 * generated decoders: same values bit for bit for random messages of growing and shrinking size,
 * and truncated or foreign buffers are rejected. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "scene_msg.h"

#include "test_util.h"

static double rnd(void) { return (double)rand() / RAND_MAX * 2.0 - 1.0; }

static void test_body_state(int n, lahar_body_state_buf *b)
{
    int32_t *id = malloc(sizeof(int32_t) * (size_t)(n + 1));
    double(*x)[3] = malloc(sizeof *x * (size_t)(n + 1)), (*q)[4] = malloc(sizeof *q * (size_t)(n + 1));
    double(*v)[3] = malloc(sizeof *v * (size_t)(n + 1)), (*w)[3] = malloc(sizeof *w * (size_t)(n + 1));
    double **px = malloc(sizeof(double *) * (size_t)(n + 1)), **pq = malloc(sizeof(double *) * (size_t)(n + 1));
    double **pv = malloc(sizeof(double *) * (size_t)(n + 1)), **pw = malloc(sizeof(double *) * (size_t)(n + 1));
    for (int i = 0; i < n; i++) {
        id[i] = 3 * i + 1;
        for (int a = 0; a < 3; a++) {
            x[i][a] = rnd();
            v[i][a] = rnd();
            w[i][a] = rnd();
        }
        for (int a = 0; a < 4; a++)
            q[i][a] = rnd();
        px[i] = x[i];
        pq[i] = q[i];
        pv[i] = v[i];
        pw[i] = w[i];
    }
    lahar_body_state_t m = {.run_id = 77, .step = n, .t = 0.125 * n, .n = n, .id = id, .x = px, .q = pq, .v = pv, .w = pw};
    int size = lahar_body_state_t_encoded_size(&m);
    void *buf = malloc((size_t)size);
    lahar_body_state_t_encode(buf, 0, size, &m);
    lahar_body_state_t ref;
    CHECK(lahar_body_state_t_decode(buf, 0, size, &ref) == size, "generated decoder failed");
    CHECK(lahar_body_state_decode(buf, size, b) == 0, "body_state n=%d not decoded", n);
    CHECK(b->run_id == 77 && b->step == n && b->t == 0.125 * n && b->n == n, "body_state header n=%d", n);
    for (int i = 0; i < n && i < b->n; i++) {
        CHECK(b->id[i] == ref.id[i], "id[%d]", i);
        CHECK(!memcmp(b->x[i], ref.x[i], sizeof b->x[i]) && !memcmp(b->q[i], ref.q[i], sizeof b->q[i]) &&
                  !memcmp(b->v[i], ref.v[i], sizeof b->v[i]) && !memcmp(b->w[i], ref.w[i], sizeof b->w[i]),
              "body %d of %d differs from LCM's decoder", i, n);
    }
    CHECK(lahar_body_state_decode(buf, size - 1, b) != 0, "truncated body_state accepted (n=%d)", n);
    lahar_body_state_t_decode_cleanup(&ref);
    free(buf);
    free(id); free(x); free(q); free(v); free(w); free(px); free(pq); free(pv); free(pw);
}

static void test_loads(int n, int np, lahar_loads_buf *b)
{
    lahar_loads_t m = {.run_id = 5, .step = 9, .nbody = n, .ntotal = np};
    m.body_id = malloc(sizeof(int32_t) * (size_t)(n + 1));
    m.npoints = malloc(sizeof(int32_t) * (size_t)(n + 1));
    m.force = malloc(sizeof(double *) * (size_t)(n + 1));
    m.torque = malloc(sizeof(double *) * (size_t)(n + 1));
    m.point_x = malloc(sizeof(double *) * (size_t)(np + 1));
    m.point_f = malloc(sizeof(double *) * (size_t)(np + 1));
    double(*rows)[3] = malloc(sizeof *rows * (size_t)(2 * n + 2 * np + 1));
    for (int i = 0; i < 2 * n + 2 * np; i++)
        for (int a = 0; a < 3; a++)
            rows[i][a] = rnd();
    for (int i = 0; i < n; i++) {
        m.body_id[i] = i * 2;
        m.npoints[i] = i == 0 ? np : 0;
        m.force[i] = rows[i];
        m.torque[i] = rows[n + i];
    }
    for (int i = 0; i < np; i++) {
        m.point_x[i] = rows[2 * n + i];
        m.point_f[i] = rows[2 * n + np + i];
    }
    int size = lahar_loads_t_encoded_size(&m);
    void *buf = malloc((size_t)size);
    lahar_loads_t_encode(buf, 0, size, &m);
    CHECK(lahar_loads_decode(buf, size, b) == 0, "loads %d/%d not decoded", n, np);
    CHECK(b->run_id == 5 && b->step == 9 && b->nbody == n && b->ntotal == np, "loads header");
    for (int i = 0; i < n && i < b->nbody; i++)
        CHECK(b->body_id[i] == 2 * i && b->npoints[i] == m.npoints[i] && !memcmp(b->force[i], m.force[i], 24) &&
                  !memcmp(b->torque[i], m.torque[i], 24),
              "loads body %d", i);
    for (int i = 0; i < np && i < b->ntotal; i++)
        CHECK(!memcmp(b->point_x[i], m.point_x[i], 24) && !memcmp(b->point_f[i], m.point_f[i], 24), "point %d", i);
    CHECK(lahar_loads_decode(buf, size - 8, b) != 0, "truncated loads accepted");
    /* a message of another type must not pass for LOADS */
    lahar_body_state_buf other = {0};
    CHECK(lahar_body_state_decode(buf, size, &other) != 0, "LOADS decoded as BODY_STATE");
    lahar_body_state_buf_free(&other);
    free(buf);
    free(rows);
    free(m.body_id); free(m.npoints); free(m.force); free(m.torque); free(m.point_x); free(m.point_f);
}

int main(void)
{
    srand(12345);
    lahar_body_state_buf b = {0};
    const int sizes[] = {0, 1, 5, 300, 17, 2000, 3};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++)
        test_body_state(sizes[i], &b);
    CHECK(b.cap >= 2000, "buffer did not grow (cap %d)", b.cap);
    lahar_body_state_buf_free(&b);
    lahar_loads_buf l = {0};
    test_loads(0, 0, &l);
    test_loads(4, 100, &l);
    test_loads(1000, 5, &l);
    test_loads(2, 0, &l);
    lahar_loads_buf_free(&l);
    if (failures)
        return 1;
    printf("PASS test_coupling_msg\n");
    return 0;
}
