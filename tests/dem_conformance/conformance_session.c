/* The harness's side of a run (conformance_session.h): coordinator and SPH node in one thread,
 * two links, the engine as a child process in the harness's private network namespace. */
#define _GNU_SOURCE
#include "conformance_session.h"
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>
#include "case.h"
#include "lahar_hello_t.h"
#include "lahar_loads_t.h"
#include "lahar_scene_t.h"
#include "lahar_status_t.h"
#include "lahar_step_t.h"
#include "lahar_stop_t.h"
#include "msg_check.h"
#include "scene_msg.h"

#define HELLO_PERIOD_MS 100     /* lcm_types/README.md: the coordinator repeats its HELLO */
#define STEP_RESEND_MS 250      /* ... and STEP(k) while STATUS(k) is missing */
#define SETUP_TIMEOUT_S 30.0    /* HELLO answer and STATUS(-1) */
#define STEP_TIMEOUT_S 20.0     /* one step (generous: sanitizer builds are slow) */

/* ---- a transport that loses frames -------------------------------------------------------- */

static int lossy_publish(void *impl, const char *channel, const void *data, size_t size)
{
    conf_lossy *l = impl;
    uint64_t n = l->published++;
    if (l->every > 0 && (n + (uint64_t)l->phase) % (uint64_t)l->every == 0) {
        l->dropped_out++;
        return 0; /* lost on the way: the sender does not know */
    }
    return lahar_transport_publish(l->inner, channel, data, size);
}

static void lossy_recv(const char *channel, const void *data, size_t size, void *user)
{
    conf_lossy *l = user;
    uint64_t n = l->heard++;
    if (l->every > 0 && (n + (uint64_t)l->phase + 3) % (uint64_t)l->every == 0) {
        l->dropped_in++;
        return;
    }
    l->fn(channel, data, size, l->user);
}

static int lossy_subscribe(void *impl, const char *regex, int queue_capacity, lahar_transport_recv_fn fn, void *user)
{
    conf_lossy *l = impl;
    l->fn = fn;
    l->user = user;
    return lahar_transport_subscribe(l->inner, regex, queue_capacity, lossy_recv, l);
}

static int lossy_handle(void *impl, int timeout_ms)
{
    conf_lossy *l = impl;
    return lahar_transport_handle(l->inner, timeout_ms);
}

static void lossy_close(void *impl) { (void)impl; }

static const lahar_transport_ops lossy_ops = {
    .scheme = "lossy+", .open = NULL, .publish = lossy_publish, .subscribe = lossy_subscribe,
    .handle = lossy_handle, .close = lossy_close,
};

static int lossy_open(conf_lossy *l, const char *url, int every, int phase, char *err, size_t errlen)
{
    memset(l, 0, sizeof *l);
    l->inner = lahar_transport_open(url, err, errlen);
    if (!l->inner)
        return -1;
    l->every = every;
    l->phase = phase;
    l->outer.ops = &lossy_ops;
    l->outer.impl = l;
    return 0;
}

/* ---- helpers ------------------------------------------------------------------------------- */

static void sess_fail(conf_session *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
#include <stdarg.h>
static void sess_fail(conf_session *s, const char *fmt, ...)
{
    if (s->fail[0])
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(s->fail, sizeof s->fail, fmt, ap);
    va_end(ap);
}

/* 1 if the engine has exited (recorded once). */
static int sess_reap(conf_session *s)
{
    if (s->exited || s->pid <= 0)
        return s->exited;
    int st;
    pid_t r = waitpid(s->pid, &st, WNOHANG);
    if (r == s->pid) {
        s->exited = 1;
        s->exit_time = lahar_now();
        s->exit_status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + (WIFSIGNALED(st) ? WTERMSIG(st) : 0);
    }
    return s->exited;
}

static int64_t random_run_id(void)
{
    uint64_t v = 0;
    int fd = open("/dev/urandom", O_RDONLY | O_CLOEXEC);
    if (fd >= 0) {
        if (read(fd, &v, sizeof v) != (ssize_t)sizeof v)
            v = 0;
        close(fd);
    }
    if (v == 0)
        v = (uint64_t)getpid() * 6364136223846793005ull + (uint64_t)(lahar_now() * 1e9);
    v &= INT64_MAX;
    return v ? (int64_t)v : 1;
}

/* Wait for (sender, type, step) on `l`, serving the other link meanwhile; while a STATUS(k >= 0)
 * is missing, STEP(k) goes out again every 250 ms as the coordinator does. 0, or -1 (s->fail). */
static int sess_wait(conf_session *s, lahar_link *l, int sender, int type, int64_t step, double timeout_s,
                     lahar_link_msg *out)
{
    lahar_link *other = l == s->co ? s->sph : s->co;
    double start = lahar_now(), resend = start + 1e-3 * STEP_RESEND_MS;
    for (;;) {
        int rc = lahar_link_wait(l, sender, type, step, 20, out);
        if (rc == LAHAR_LINK_OK)
            return 0;
        if (rc != LAHAR_LINK_TIMEOUT) {
            sess_fail(s, "link error %d waiting for %s(%lld)", rc, lahar_link_channel(type), (long long)step);
            return -1;
        }
        lahar_link_poll(other, 1);
        double now = lahar_now();
        if (type == LAHAR_FRAME_T_MSG_STATUS && step >= 0 && now >= resend) {
            lahar_link_republish(s->co, LAHAR_FRAME_T_MSG_STEP, step);
            resend = now + 1e-3 * STEP_RESEND_MS;
        }
        if (sess_reap(s)) {
            sess_fail(s, "the engine exited (status %d) while the harness waited for %s(%lld) (log: %s/engine.log)",
                      s->exit_status, lahar_link_channel(type), (long long)step, s->out);
            return -1;
        }
        if (now - start > timeout_s) {
            sess_fail(s, "no %s(%lld) from the engine within %.0f s", lahar_link_channel(type), (long long)step,
                      timeout_s);
            return -1;
        }
    }
}

static int sess_spawn(conf_session *s)
{
    char log[1200];
    snprintf(log, sizeof log, "%s/engine.log", s->out);
    pid_t pid = fork();
    if (pid < 0) {
        sess_fail(s, "fork failed");
        return -1;
    }
    if (pid == 0) {
        prctl(PR_SET_PDEATHSIG, SIGKILL); /* never outlive the harness */
        /* only async-signal-safe calls here (the harness has threads); LCM_DEFAULT_URL is set in
         * the harness's own environment before any thread exists */
        int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
        if (fd >= 0) {
            dup2(fd, 1);
            dup2(fd, 2);
        }
        execvp(s->cmd[0], (char *const *)s->cmd);
        static const char msg[] = "dem_conformance: cannot execute the engine command\n";
        if (write(2, msg, sizeof msg - 1) < 0)
            _exit(127);
        _exit(127);
    }
    s->pid = pid;
    return 0;
}

static int sess_alloc(conf_session *s, int64_t max_steps)
{
    s->moving = calloc((size_t)(s->c.nbody > 0 ? s->c.nbody : 1), sizeof *s->moving);
    if (!s->moving)
        return -1;
    for (int i = 0; i < s->c.nbody; i++)
        if (s->c.bodies[i].motion != LAHAR_MOTION_FIXED)
            s->moving[s->nmoving++] = i;
    s->cap = max_steps > 0 ? max_steps : 1;
    size_t rows = (size_t)s->cap * (size_t)(s->nmoving > 0 ? s->nmoving : 1);
    s->t = calloc((size_t)s->cap, sizeof *s->t);
    s->nsub = calloc((size_t)s->cap, sizeof *s->nsub);
    s->status_dt_stable = calloc((size_t)s->cap, sizeof *s->status_dt_stable);
    s->x = calloc(rows, sizeof *s->x);
    s->v = calloc(rows, sizeof *s->v);
    s->w = calloc(rows, sizeof *s->w);
    s->q = calloc(rows, sizeof *s->q);
    return s->t && s->nsub && s->status_dt_stable && s->x && s->v && s->w && s->q ? 0 : -1;
}

/* ---- the run ------------------------------------------------------------------------------- */

int conf_session_start(conf_session *s, const char *case_path, const char *out_dir, int64_t max_steps)
{
    char err[2048];
    s->fail[0] = '\0';
    snprintf(s->case_path, sizeof s->case_path, "%s", case_path);
    snprintf(s->out, sizeof s->out, "%s", out_dir);
    if (lahar_case_load_err(case_path, &s->c, err, sizeof err) != 0) {
        sess_fail(s, "%s", err);
        return -1;
    }
    snprintf(s->c.dem_engine, sizeof s->c.dem_engine, "%s", s->engine);
    if (sess_alloc(s, max_steps) != 0) {
        sess_fail(s, "out of memory");
        return -1;
    }
    s->run_id = random_run_id();
    if (lossy_open(&s->lc, s->url, s->drop_every, 0, err, sizeof err) != 0 ||
        lossy_open(&s->ls, s->url, s->drop_every, 2, err, sizeof err) != 0) {
        sess_fail(s, "%s", err);
        return -1;
    }
    s->co = lahar_link_create(&s->lc.outer, LAHAR_ROLE_COORDINATOR, s->run_id,
                              LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_HELLO) | LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_STATUS), err,
                              sizeof err);
    s->sph = s->co ? lahar_link_create(&s->ls.outer, LAHAR_ROLE_SPH, s->run_id,
                                       LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_BODY_STATE), err, sizeof err)
                   : NULL;
    if (!s->co || !s->sph || lahar_link_heartbeat_start(s->co, LAHAR_HEARTBEAT_PERIOD) != 0 ||
        lahar_link_heartbeat_start(s->sph, LAHAR_HEARTBEAT_PERIOD) != 0) {
        sess_fail(s, "cannot open the harness's links: %s", err);
        return -1;
    }
    if (sess_spawn(s) != 0)
        return -1;

    /* HELLO, repeated until the DEM node answers */
    char host[256] = "";
    gethostname(host, sizeof host - 1);
    lahar_hello_t h = {
        .run_id = s->run_id, .step = -1, .role = LAHAR_ROLE_COORDINATOR, .engine = "dem_conformance",
        .version = LAHAR_VERSION, .protocol_version = 1, .ncapabilities = 0, .capabilities = NULL, .host = host,
        .pid = (int32_t)getpid(),
    };
    int rc;
    LAHAR_LINK_SEND(rc, s->co, LAHAR_FRAME_T_MSG_HELLO, lahar_hello_t, -1, &h);
    if (rc != 0) {
        sess_fail(s, "cannot publish on %s", s->url);
        return -1;
    }
    lahar_link_msg m;
    double until = lahar_now() + SETUP_TIMEOUT_S;
    for (;;) {
        rc = lahar_link_wait(s->co, LAHAR_ROLE_DEM, LAHAR_FRAME_T_MSG_HELLO, -1, HELLO_PERIOD_MS, &m);
        if (rc == LAHAR_LINK_OK)
            break;
        lahar_link_poll(s->sph, 1);
        if (sess_reap(s)) {
            sess_fail(s, "the engine exited (status %d) before answering the HELLO (log: %s/engine.log)",
                      s->exit_status, s->out);
            return -1;
        }
        if (lahar_now() > until) {
            sess_fail(s, "the engine did not answer the HELLO within %.0f s", SETUP_TIMEOUT_S);
            return -1;
        }
        lahar_link_republish(s->co, LAHAR_FRAME_T_MSG_HELLO, -1);
    }
    lahar_hello_t hr;
    if (LAHAR_MSG_DECODE(lahar_hello_t, m.data, m.size, &hr) < 0) {
        sess_fail(s, "undecodable hello_t from the engine");
        return -1;
    }
    snprintf(s->hello_engine, sizeof s->hello_engine, "%s", hr.engine ? hr.engine : "");
    snprintf(s->hello_version, sizeof s->hello_version, "%s", hr.version ? hr.version : "");
    snprintf(s->hello_host, sizeof s->hello_host, "%s", hr.host ? hr.host : "");
    s->hello_role = hr.role;
    s->hello_protocol = hr.protocol_version;
    s->hello_pid = hr.pid;
    s->hello_ncaps = hr.ncapabilities;
    s->hello_run_id = hr.run_id;
    lahar_hello_t_decode_cleanup(&hr);

    /* SCENE: the engine's bodies, and an SPH side without particles (has_sph = 1: LOADS(k) in,
     * BODY_STATE(k) out every step) */
    lahar_scene_t sm;
    if (lahar_scene_msg_from_case(&s->c, s->out, 1, 1, s->run_id, &sm) != 0) {
        sess_fail(s, "cannot build the scene message of %s", case_path);
        return -1;
    }
    LAHAR_LINK_SEND(rc, s->co, LAHAR_FRAME_T_MSG_SCENE, lahar_scene_t, -1, &sm);
    lahar_scene_msg_release(&sm);
    if (rc != 0) {
        sess_fail(s, "cannot publish the scene");
        return -1;
    }
    if (sess_wait(s, s->co, LAHAR_ROLE_DEM, LAHAR_FRAME_T_MSG_STATUS, -1, SETUP_TIMEOUT_S, &m) != 0)
        return -1;
    lahar_status_t st;
    if (LAHAR_MSG_DECODE(lahar_status_t, m.data, m.size, &st) < 0) {
        sess_fail(s, "undecodable STATUS(-1)");
        return -1;
    }
    memcpy(s->ready_message, st.message, sizeof s->ready_message);
    s->ready_message[sizeof s->ready_message - 1] = '\0';
    s->dt_stable = st.dt_stable;
    int error = st.error, role = st.role;
    int64_t step = st.step;
    lahar_status_t_decode_cleanup(&st);
    if (error) {
        sess_fail(s, "the engine refused the scene: %s", s->ready_message);
        return -1;
    }
    if (role != LAHAR_ROLE_DEM || step != -1) {
        sess_fail(s, "STATUS(-1) carries role %d step %lld (expected 1, -1)", role, (long long)step);
        return -1;
    }
    return 0;
}

int conf_session_step(conf_session *s, int64_t k, double t, double t_next, const lahar_body_load *loads)
{
    if (k >= s->cap) {
        sess_fail(s, "harness: more steps than allocated");
        return -1;
    }
    lahar_step_t step = {
        .run_id = s->run_id, .step = k, .t = t, .dt = t_next - t, .t_next = t_next, .write_output = 0,
        .write_forces = 0, .checkpoint = 0,
    };
    int rc;
    LAHAR_LINK_SEND(rc, s->co, LAHAR_FRAME_T_MSG_STEP, lahar_step_t, k, &step);
    if (rc != 0) {
        sess_fail(s, "cannot publish STEP(%lld)", (long long)k);
        return -1;
    }
    /* LOADS(k): every moving body, reach everywhere (so BODY_STATE lists them all) */
    enum { MAXB = 64 };
    int32_t ids[MAXB], npts[MAXB];
    double frow[MAXB][3], trow[MAXB][3];
    double *fp[MAXB], *tp[MAXB];
    int nb = 0;
    for (int i = 0; i < s->nmoving && nb < MAXB; i++, nb++) {
        int b = s->moving[i];
        ids[nb] = b;
        npts[nb] = 0;
        for (int a = 0; a < 3; a++) {
            frow[nb][a] = loads ? loads[b].force[a] : 0.0;
            trow[nb][a] = loads ? loads[b].torque[a] : 0.0;
        }
        fp[nb] = frow[nb];
        tp[nb] = trow[nb];
    }
    lahar_loads_t lm = {
        .run_id = s->run_id, .step = k, .nbody = nb, .body_id = ids, .force = fp, .torque = tp, .npoints = npts,
        .ntotal = 0, .point_x = NULL, .point_f = NULL,
        .reach_lo = {-1e300, -1e300, -1e300}, .reach_hi = {1e300, 1e300, 1e300},
    };
    LAHAR_LINK_SEND(rc, s->sph, LAHAR_FRAME_T_MSG_LOADS, lahar_loads_t, k, &lm);
    if (rc != 0) {
        sess_fail(s, "cannot publish LOADS(%lld)", (long long)k);
        return -1;
    }
    lahar_link_msg m;
    if (sess_wait(s, s->co, LAHAR_ROLE_DEM, LAHAR_FRAME_T_MSG_STATUS, k, STEP_TIMEOUT_S, &m) != 0)
        return -1;
    lahar_status_t st;
    if (LAHAR_MSG_DECODE(lahar_status_t, m.data, m.size, &st) < 0) {
        sess_fail(s, "undecodable STATUS(%lld)", (long long)k);
        return -1;
    }
    int error = st.error, role = st.role;
    int64_t sstep = st.step;
    s->nsub[k] = st.nsubsteps;
    s->status_dt_stable[k] = st.dt_stable;
    char msg[512];
    memcpy(msg, st.message, sizeof msg);
    msg[sizeof msg - 1] = '\0';
    lahar_status_t_decode_cleanup(&st);
    if (error) {
        sess_fail(s, "STATUS(%lld) reports an error: %s", (long long)k, msg);
        return -1;
    }
    if (sstep != k || role != LAHAR_ROLE_DEM) {
        sess_fail(s, "answer to STEP(%lld) is STATUS with step %lld role %d", (long long)k, (long long)sstep, role);
        return -1;
    }
    if (sess_wait(s, s->sph, LAHAR_ROLE_DEM, LAHAR_FRAME_T_MSG_BODY_STATE, k, STEP_TIMEOUT_S, &m) != 0)
        return -1;
    lahar_body_state_buf bs = {0};
    if (lahar_body_state_decode(m.data, m.size, &bs) != 0) {
        sess_fail(s, "undecodable BODY_STATE(%lld)", (long long)k);
        lahar_body_state_buf_free(&bs);
        return -1;
    }
    int ok = 1;
    if (bs.step != k || bs.t != t_next) {
        sess_fail(s, "BODY_STATE(%lld) carries step %lld, t = %.17g (expected t_next = %.17g)", (long long)k,
                  (long long)bs.step, bs.t, t_next);
        ok = 0;
    } else if (bs.n != s->nmoving) {
        sess_fail(s, "BODY_STATE(%lld) lists %d bodies, the scene has %d moving ones (reach covers all)",
                  (long long)k, bs.n, s->nmoving);
        ok = 0;
    }
    s->t[k] = bs.t;
    for (int i = 0; ok && i < bs.n; i++) {
        int j = 0;
        while (j < s->nmoving && s->moving[j] != bs.id[i])
            j++;
        if (j == s->nmoving) {
            sess_fail(s, "BODY_STATE(%lld) lists body %d, not a moving body of the scene", (long long)k, bs.id[i]);
            ok = 0;
            break;
        }
        size_t r = (size_t)k * (size_t)s->nmoving + (size_t)j;
        memcpy(s->x[r], bs.x[i], sizeof s->x[r]);
        memcpy(s->v[r], bs.v[i], sizeof s->v[r]);
        memcpy(s->w[r], bs.w[i], sizeof s->w[r]);
        memcpy(s->q[r], bs.q[i], sizeof s->q[r]);
    }
    lahar_body_state_buf_free(&bs);
    if (!ok)
        return -1;
    s->nsteps = k + 1;
    return 0;
}

void conf_session_idle(conf_session *s, int ms)
{
    double until = lahar_now() + 1e-3 * ms;
    while (lahar_now() < until) {
        lahar_link_poll(s->co, 10);
        lahar_link_poll(s->sph, 1);
    }
}

int conf_session_stop(conf_session *s, double timeout_s)
{
    lahar_stop_t stop = {.run_id = s->run_id, .step = s->nsteps - 1, .reason = 0, .message = "finished"};
    int rc;
    LAHAR_LINK_SEND(rc, s->co, LAHAR_FRAME_T_MSG_STOP, lahar_stop_t, stop.step, &stop);
    (void)rc;
    double start = lahar_now(), next = start + 0.1;
    while (!sess_reap(s)) {
        lahar_link_poll(s->co, 10);
        lahar_link_poll(s->sph, 1);
        double now = lahar_now();
        if (now - start > timeout_s)
            return -1;
        if (now >= next) {
            lahar_link_republish(s->co, LAHAR_FRAME_T_MSG_STOP, stop.step);
            next = now + 0.1;
        }
    }
    return 0;
}

int conf_session_wait_exit(conf_session *s, double timeout_s)
{
    double start = lahar_now();
    while (!sess_reap(s)) {
        if (lahar_now() - start > timeout_s)
            return -1;
        usleep(5000);
    }
    return 0;
}

void conf_session_free(conf_session *s)
{
    if (s->pid > 0 && !sess_reap(s)) {
        kill(s->pid, SIGKILL);
        waitpid(s->pid, NULL, 0);
        s->exited = 1;
    }
    if (s->co)
        lahar_link_heartbeat_stop(s->co);
    if (s->sph)
        lahar_link_heartbeat_stop(s->sph);
    lahar_link_destroy(s->co);
    lahar_link_destroy(s->sph);
    if (s->lc.inner)
        lahar_transport_close(s->lc.inner);
    if (s->ls.inner)
        lahar_transport_close(s->ls.inner);
    lahar_case_free(&s->c);
    free(s->moving);
    free(s->t);
    free(s->nsub);
    free(s->status_dt_stable);
    free(s->x);
    free(s->v);
    free(s->w);
    free(s->q);
    s->co = s->sph = NULL;
    s->moving = NULL;
}
