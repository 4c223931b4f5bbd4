/* Checkpoints (case section checkpoint:; coordinator/README.md "Checkpoints and resume"): the
 * coordinator's part of one, written atomically beside the nodes' parts; the case kept with them;
 * and `lahar resume`, which continues from the newest. */
#define _GNU_SOURCE
#include <dirent.h>
#include <errno.h>
#include <libgen.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include "checkpoint.h"
#include "coord_run.h"
#include "output.h"

/* The coordinator's part of a checkpoint (common/io/checkpoint.h; one function both ways): the step
 * and time, the clock, the next step's limit and the first step (dt collapse), whether the state
 * is a scheduled snapshot, and the totals summary.json continues. */
static int coord_state_io(coord *co, lahar_ckpt_file *f, int64_t *k, lahar_clock *clk, double *dt_allowed,
                          double *dt_first, int *is_output)
{
    lahar_ckpt_i64(f, "step", k, 1);
    lahar_ckpt_f64(f, "t", &co->sim_time, 1);
    double cd[4] = {clk->t_end, clk->out_interval, clk->t_base, clk->h};
    int64_t ci[4] = {clk->nout, clk->j, clk->i, clk->m};
    lahar_ckpt_f64(f, "clock_t_end_interval_base_h", cd, 4);
    lahar_ckpt_i64(f, "clock_nout_j_i_m", ci, 4);
    double dts[2] = {*dt_allowed, *dt_first};
    lahar_ckpt_f64(f, "dt_allowed_first", dts, 2);
    lahar_ckpt_int(f, "snapshot_at_step", is_output);
    lahar_ckpt_i64(f, "steps", &co->steps, 1);
    int64_t run_id = co->run_id;
    lahar_ckpt_i64(f, "run_id", &run_id, 1);
    for (int r = 1; r < LAHAR_NROLES; r++) {
        coord_node *n = &co->node[r];
        char name[48];
        double nf[5] = {n->compute_s, n->wait_s, n->dt_proposed, n->dt_stable, n->kinetic_energy};
        int64_t ni[4] = {n->substeps, n->last_step, n->ncontacts, n->needed};
        snprintf(name, sizeof name, "node%d_compute_wait_dtp_dts_ke", r);
        lahar_ckpt_f64(f, name, nf, 5);
        snprintf(name, sizeof name, "node%d_substeps_last_contacts_needed", r);
        lahar_ckpt_i64(f, name, ni, 4);
        if (!f->writing && !f->failed) {
            n->compute_s = nf[0], n->wait_s = nf[1], n->dt_proposed = nf[2], n->dt_stable = nf[3];
            n->kinetic_energy = nf[4];
            n->substeps = ni[0], n->last_step = ni[1], n->ncontacts = (int)ni[2];
            if (ni[3] != n->needed) {
                snprintf(f->err, sizeof f->err, "the checkpoint's run %s a %s, this case %s (another case?)",
                         ni[3] ? "had" : "had no", lahar_link_role_name(r), n->needed ? "needs one" : "none");
                f->failed = 1;
            }
        }
    }
    if (!f->writing && !f->failed) {
        clk->t_end = cd[0], clk->out_interval = cd[1], clk->t_base = cd[2], clk->h = cd[3];
        clk->nout = ci[0], clk->j = ci[1], clk->i = ci[2], clk->m = ci[3];
        *dt_allowed = dts[0], *dt_first = dts[1];
        snprintf(co->resume_run_id, sizeof co->resume_run_id, "%016llx", (unsigned long long)run_id);
    }
    return f->failed ? -1 : 0;
}

/* Remove a directory and what it holds (checkpoints/ holds NNNNNN/ directories of files). 0, or -1
 * with errno set when the directory itself could not be removed. */
int coord_rm_ckpt_dir(const char *path)
{
    DIR *d = opendir(path);
    if (d) {
        struct dirent *e;
        while ((e = readdir(d)) != NULL) {
            if (e->d_name[0] == '.')
                continue;
            char p[4400];
            snprintf(p, sizeof p, "%.4000s/%.255s", path, e->d_name);
            if (unlink(p) != 0)
                coord_rm_ckpt_dir(p);
        }
        closedir(d);
    }
    return rmdir(path);
}

/* The checkpoints in OUT/checkpoints: the step indices of the complete ones (NNNNNN holding
 * coord.h5), newest first, into steps (up to cap); *.tmp ones (an interrupted checkpoint) are
 * removed when remove_tmp. Returns the count. */
static int coord_list_ckpts(const char *outdir, int64_t *steps, int cap, int remove_tmp)
{
    char dir[PATH_MAX + 32];
    snprintf(dir, sizeof dir, "%s/" LAHAR_CKPT_DIR, outdir);
    DIR *d = opendir(dir);
    if (!d)
        return 0;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        char *end;
        if (e->d_name[0] < '0' || e->d_name[0] > '9')
            continue;
        long long st = strtoll(e->d_name, &end, 10);
        char path[PATH_MAX + 320];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (strcmp(end, ".tmp") == 0) {
            if (remove_tmp)
                coord_rm_ckpt_dir(path);
            continue;
        }
        char coordf[PATH_MAX + 340];
        snprintf(coordf, sizeof coordf, "%s/coord.h5", path);
        if (*end || access(coordf, R_OK) != 0 || n >= cap)
            continue;
        steps[n++] = st;
    }
    closedir(d);
    for (int i = 0; i < n; i++) /* newest first */
        for (int j = i + 1; j < n; j++)
            if (steps[j] > steps[i]) {
                int64_t t = steps[i];
                steps[i] = steps[j];
                steps[j] = t;
            }
    return n;
}

/* After STATUS(k) of a step that carried the checkpoint flag (state K = k + 1): every node has
 * written and synced NNNNNN.tmp/<role>.h5; write coord.h5 there, sync it and the directory,
 * rename NNNNNN.tmp -> NNNNNN (atomic), sync OUT/checkpoints, and keep the newest
 * checkpoint.keep. A crash at any moment leaves the previous checkpoint or the new one
 * complete. 0, or -1 with co->message. */
int coord_checkpoint(coord *co, int64_t k, lahar_clock *clk, double dt_allowed, double dt_first, int is_output)
{
    int64_t K = k + 1;
    char tmp[PATH_MAX + 64], fin[PATH_MAX + 64], path[PATH_MAX + 96], dir[PATH_MAX + 32];
    lahar_ckpt_dir(tmp, sizeof tmp, co->outdir, K, 1);
    lahar_ckpt_dir(fin, sizeof fin, co->outdir, K, 0);
    snprintf(dir, sizeof dir, "%s/" LAHAR_CKPT_DIR, co->outdir);
    for (int r = 1; r < LAHAR_NROLES; r++)
        if (co->node[r].needed && !co->node[r].checkpointed) {
            snprintf(co->message, sizeof co->message, "the %s did not write its checkpoint of step %lld",
                     lahar_link_role_name(r), (long long)K);
            return -1;
        }
    if (lahar_mkdir_p(tmp) != 0) {
        snprintf(co->message, sizeof co->message, "cannot create %.900s: %s", tmp, strerror(errno));
        return -1;
    }
    snprintf(path, sizeof path, "%s/coord.h5", tmp);
    lahar_ckpt_file f;
    int64_t kk = K;
    if (lahar_ckpt_create(&f, path, "coordinator") == 0)
        coord_state_io(co, &f, &kk, clk, &dt_allowed, &dt_first, &is_output);
    if (lahar_ckpt_close(&f) != 0) {
        snprintf(co->message, sizeof co->message, "%.1000s", f.err);
        return -1;
    }
    if (access(fin, F_OK) == 0) /* a checkpoint of this step from before a resume: replaced */
        coord_rm_ckpt_dir(fin);
    if (lahar_ckpt_fsync_path(tmp) != 0 || rename(tmp, fin) != 0 || lahar_ckpt_fsync_path(dir) != 0) {
        snprintf(co->message, sizeof co->message, "cannot complete the checkpoint %.900s: %s", fin, strerror(errno));
        return -1;
    }
    co->ckpt_written++;
    co->ckpt_last_step = K;
    co->ckpt_last_t = co->sim_time;
    int64_t steps[1024];
    int n = coord_list_ckpts(co->outdir, steps, 1024, 0);
    int keep = co->c->checkpoint_keep > 0 ? co->c->checkpoint_keep : 2;
    for (int i = keep; i < n; i++) {
        lahar_ckpt_dir(path, sizeof path, co->outdir, steps[i], 0);
        coord_rm_ckpt_dir(path);
    }
    if (n > keep)
        lahar_ckpt_fsync_path(dir);
    return 0;
}

/* A run with checkpoints keeps the case it was started with in OUT/checkpoints: case.yaml (a
 * byte copy) and case_source (the original path and the directory its relative paths start
 * from), so that `lahar resume OUT` needs nothing else. 0 or -1 (message on stderr). */
int coord_save_case(const char *outdir, const lahar_case *c)
{
    char dir[PATH_MAX + 32], path[PATH_MAX + 64], src_dir[PATH_MAX];
    snprintf(dir, sizeof dir, "%s/" LAHAR_CKPT_DIR, outdir);
    if (lahar_mkdir_p(dir) != 0) {
        fprintf(stderr, "lahar: cannot create %s: %s\n", dir, strerror(errno));
        return -1;
    }
    char tmp[PATH_MAX];
    snprintf(tmp, sizeof tmp, "%s", c->path);
    if (!realpath(dirname(tmp), src_dir))
        snprintf(src_dir, sizeof src_dir, ".");
    FILE *in = fopen(c->path, "rb");
    snprintf(path, sizeof path, "%s/case.yaml", dir);
    FILE *out = in ? fopen(path, "wb") : NULL;
    int rc = in && out ? 0 : -1;
    char buf[65536];
    size_t n;
    while (!rc && (n = fread(buf, 1, sizeof buf, in)) > 0)
        if (fwrite(buf, 1, n, out) != n)
            rc = -1;
    if (in)
        fclose(in);
    if (out && fclose(out) != 0)
        rc = -1;
    snprintf(path, sizeof path, "%s/case_source", dir);
    char abs[PATH_MAX];
    if (!realpath(c->path, abs))
        snprintf(abs, sizeof abs, "%s", c->path);
    out = rc ? NULL : fopen(path, "w");
    if (!out || fprintf(out, "%s\n%s\n", abs, src_dir) < 0)
        rc = -1;
    if (out && fclose(out) != 0)
        rc = -1;
    if (rc)
        fprintf(stderr, "lahar: cannot keep a copy of the case %s in %s: %s\n", c->path, dir, strerror(errno));
    return rc;
}

int lahar_coord_resume_case(const char *outdir, lahar_case *c)
{
    char path[PATH_MAX + 64], src[PATH_MAX + 64], line1[PATH_MAX], line2[PATH_MAX];
    struct stat st;
    const int missing = stat(outdir, &st) != 0;
    if (missing || !S_ISDIR(st.st_mode)) { /* a case file, or a mistyped OUT */
        const int e = errno;
        const size_t len = strlen(outdir);
        const int yaml = len > 5 && strcmp(outdir + len - 5, ".yaml") == 0;
        fprintf(stderr, "lahar resume: %s: %s; resume takes the output directory of a run (lahar resume OUT)%s\n",
                outdir, missing ? strerror(e) : "not a directory",
                yaml ? ", not its case: to start the case, lahar run CASE.yaml -o OUT" : "");
        return LAHAR_EXIT_SETUP;
    }
    snprintf(src, sizeof src, "%s/" LAHAR_CKPT_DIR "/case_source", outdir);
    FILE *f = fopen(src, "r");
    if (!f) {
        fprintf(stderr, "lahar resume: %s has no checkpoints (no %s: the run's case had no checkpoint: section, "
                        "or this is not a lahar output directory); start it again with `lahar run CASE -o %s "
                        "--overwrite`\n", outdir, src, outdir);
        return LAHAR_EXIT_SETUP;
    }
    int ok = fgets(line1, sizeof line1, f) && fgets(line2, sizeof line2, f);
    fclose(f);
    if (!ok) {
        fprintf(stderr, "lahar resume: %s is incomplete; start the run again with lahar run --overwrite\n", src);
        return LAHAR_EXIT_SETUP;
    }
    line1[strcspn(line1, "\n")] = '\0';
    line2[strcspn(line2, "\n")] = '\0';
    snprintf(path, sizeof path, "%s/" LAHAR_CKPT_DIR "/case.yaml", outdir);
    char err[2048];
    if (lahar_case_load_dir(path, line2, c, err, sizeof err) != 0) {
        fprintf(stderr, "lahar resume: %s (the run's case, kept in %s; its files are read from %s)\n", err, path,
                line2);
        return LAHAR_EXIT_SETUP;
    }
    snprintf(c->path, sizeof c->path, "%.1023s", line1);
    return 0;
}

/* `lahar resume`: the newest complete checkpoint of OUT (stale *.tmp removed), its coordinator
 * state, the output cut back to it; fills the resume fields of rc. 0, or -1 with a message on
 * stderr (status 2). 1: nothing to do (the checkpoint is at the end time). */
int coord_resume_prepare(coord *co, lahar_case *rc, double t_end)
{
    int64_t steps[1024];
    int n = coord_list_ckpts(co->outdir, steps, 1024, 1);
    if (n == 0) {
        fprintf(stderr, "lahar resume: %s has no complete checkpoint (none was written before the run ended); "
                        "start it again with `lahar run CASE -o %s --overwrite`\n", co->outdir, co->outdir);
        return -1;
    }
    char dir[PATH_MAX + 64], path[PATH_MAX + 96];
    lahar_ckpt_dir(dir, sizeof dir, co->outdir, steps[0], 0);
    snprintf(path, sizeof path, "%s/coord.h5", dir);
    lahar_ckpt_file f;
    int64_t k = -1;
    int is_output = 0;
    if (lahar_ckpt_open(&f, path, "coordinator") == 0)
        coord_state_io(co, &f, &k, &co->clk0, &co->dt_allowed0, &co->dt_first0, &is_output);
    if (lahar_ckpt_close(&f) != 0) {
        fprintf(stderr, "lahar resume: %s\n", f.err);
        return -1;
    }
    if (k != steps[0]) {
        fprintf(stderr, "lahar resume: %s holds step %lld, not %lld\n", path, (long long)k, (long long)steps[0]);
        return -1;
    }
    co->resume_t = co->sim_time;
    if (t_end > 0.0) {
        if (!(t_end > co->resume_t) || t_end < rc->output_interval) {
            fprintf(stderr, "lahar resume: --time-end %g must be later than the checkpoint (t = %.9g s) and at least "
                            "output_interval (%g s)\n", t_end, co->resume_t, rc->output_interval);
            return -1;
        }
        rc->t_end = t_end;
    }
    if (co->resume_t >= rc->t_end * (1.0 - 1e-12)) {
        printf("lahar resume: the run in %s is at its end time already (checkpoint of step %lld, t = %.9g s); "
               "give --time-end T to extend it\n", co->outdir, (long long)k, co->resume_t);
        return 1;
    }
    if (rc->t_end != co->clk0.t_end) {
        /* a later end: the output times after the checkpoint are those of a run to the new end;
         * a segment aimed at the old end is planned again from the checkpoint's time */
        lahar_clock fresh;
        lahar_clock_init(&fresh, rc->t_end, rc->output_interval);
        double old_target = lahar_clock_output_time(&co->clk0, co->clk0.j + 1);
        co->clk0.t_end = fresh.t_end;
        co->clk0.out_interval = fresh.out_interval;
        co->clk0.nout = fresh.nout;
        if (co->clk0.m > 0 && lahar_clock_output_time(&co->clk0, co->clk0.j + 1) != old_target) {
            co->clk0.t_base = co->resume_t;
            co->clk0.i = 0;
            co->clk0.m = 0;
        }
    }
    char err[1024];
    if (lahar_output_resume_trim(co->outdir, k, is_output, err, sizeof err) != 0) {
        fprintf(stderr, "lahar resume: %s\n", err);
        return -1;
    }
    co->resumed = 1;
    co->k0 = k;
    co->steps = k;
    co->ckpt_last_step = k;
    co->ckpt_last_t = co->resume_t;
    size_t dlen = strlen(dir);
    if (dlen >= sizeof rc->resume_dir) {
        fprintf(stderr, "lahar resume: the checkpoint's path %s is longer than %zu characters\n", dir,
                sizeof rc->resume_dir - 1);
        return -1;
    }
    memcpy(co->resume_dir, dir, dlen + 1);
    rc->resume = 1;
    rc->resume_step = k;
    memcpy(rc->resume_dir, dir, dlen + 1);
    return 0;
}
