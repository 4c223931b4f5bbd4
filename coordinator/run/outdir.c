/* The output directory OUT before a run writes in it: created and locked against a second run,
 * an earlier run's files refused (or removed with --overwrite), and the room for summary.json
 * taken on the disk. */
#define _GNU_SOURCE
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <time.h>
#include <unistd.h>
#include "checkpoint.h"
#include "coord_run.h"
#include "output.h"

/* OUT/.lahar.lock, held (flock) for the whole run: a second run into the same directory is refused
 * with the holder's pid, host, start time and case (the file's text), instead of two runs writing
 * one set of HDF5 files. The lock goes with the process (also when it is killed); the file stays.
 * Returns the descriptor, or -1 after saying why (and exit status 2 is the caller's). */
static int coord_lock_outdir(const char *outdir, const char *case_path)
{
    char path[PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/.lahar.lock", outdir);
    int fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC, 0666);
    if (fd < 0) {
        fprintf(stderr, "lahar: cannot write in the output directory %s: %s; choose another -o or make it "
                        "writable\n", outdir, strerror(errno));
        return -1;
    }
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
        char text[512] = "", holder[768] = "";
        ssize_t n = pread(fd, text, sizeof text - 1, 0);
        text[n > 0 ? n : 0] = '\0';
        size_t h = 0; /* the file's lines joined by ", " */
        for (char *line = strtok(text, "\n"); line && h < sizeof holder; line = strtok(NULL, "\n"))
            h += (size_t)snprintf(holder + h, sizeof holder - h, "%s%s", h ? ", " : "", line);
        fprintf(stderr, "lahar: %s is in use by another lahar run (%s); wait for it to end, stop it, or choose "
                        "another -o\n", outdir, holder[0] ? holder : "no details");
        close(fd);
        return -1;
    }
    char host[256] = "?", when[64] = "?";
    gethostname(host, sizeof host - 1);
    time_t now = time(NULL);
    struct tm tm;
    if (gmtime_r(&now, &tm))
        strftime(when, sizeof when, "%Y-%m-%d %H:%M:%S UTC", &tm);
    char text[PATH_MAX + 640];
    int len = snprintf(text, sizeof text, "pid %ld\nhost %s\nstarted %s\ncase %s\n", (long)getpid(), host, when,
                       case_path);
    if (ftruncate(fd, 0) != 0 || pwrite(fd, text, (size_t)len, 0) != len) {
        fprintf(stderr, "lahar: cannot write in the output directory %s: %s; choose another -o or free space "
                        "there\n", outdir, strerror(errno));
        close(fd);
        return -1;
    }
    return fd;
}

/* OUT holding an earlier run's files (common/io/output.h, lahar_output_run_files) is refused, so
 * that runs never mix (a water run's particles.h5 left beside a later DEM-only run, lahar.xmf
 * pointing at both); with --overwrite those files are removed first. 0 to go on, -1 refused. */
static int coord_clear_outdir(const char *outdir, int overwrite)
{
    char path[PATH_MAX + 32], found[256] = "";
    size_t nf = 0;
    for (int i = 0; lahar_output_run_files[i]; i++) {
        snprintf(path, sizeof path, "%s/%s", outdir, lahar_output_run_files[i]);
        if (access(path, F_OK) != 0)
            continue;
        if (overwrite) {
            if (unlink(path) != 0) {
                fprintf(stderr, "lahar: --overwrite: cannot remove %s: %s\n", path, strerror(errno));
                return -1;
            }
        } else if (nf < sizeof found) {
            nf += (size_t)snprintf(found + nf, sizeof found - nf, "%s%s", nf ? ", " : "", lahar_output_run_files[i]);
        }
    }
    /* the checkpoints of an earlier run (and the copy of its case) */
    snprintf(path, sizeof path, "%s/" LAHAR_CKPT_DIR, outdir);
    DIR *d = opendir(path);
    if (d && overwrite) {
        closedir(d);
        if (coord_rm_ckpt_dir(path) != 0) {
            fprintf(stderr, "lahar: --overwrite: cannot remove %s: %s\n", path, strerror(errno));
            return -1;
        }
    } else if (d) {
        closedir(d);
        if (nf < sizeof found)
            nf += (size_t)snprintf(found + nf, sizeof found - nf, "%s" LAHAR_CKPT_DIR "/", nf ? ", " : "");
    }
    if (!found[0])
        return 0;
    fprintf(stderr, "lahar: %s holds the output of an earlier run (%s); add --overwrite to replace it (those files "
                    "are removed first),%s or choose another -o\n", outdir, found,
            strstr(found, LAHAR_CKPT_DIR) ? " continue it with `lahar resume OUT`," : "");
    return -1;
}

/* Before anything runs: OUT must have room for the first snapshots, the writers' margin and
 * summary.json, whose room is taken now (a placeholder that says the run has not ended, padded
 * to COORD_SUMMARY_RESERVE bytes), so that a run that fills the disk can still write it. A full
 * disk is refused with exit status 2. The descriptor goes to co->summary_fd. */
int coord_reserve_summary(coord *co)
{
    const lahar_case *c = co->c;
    double particles = 0.0;
    for (int b = 0; b < c->nblock; b++) {
        double cells = 1.0;
        for (int a = 0; a < c->dim; a++)
            cells *= (c->blocks[b].hi[a] - c->blocks[b].lo[a]) / c->sph_dx + 1.0;
        particles += cells;
    }
    /* a particle snapshot (17 values per particle at most), the bodies' files with their
     * geometry, the writers' margin */
    double need = 17.0 * 8.0 * particles + 64.0 * 1024.0 * (c->nbody + 1) + 2.0 * LAHAR_OUTPUT_RESERVE +
                  COORD_SUMMARY_RESERVE;
    double avail = lahar_output_free_bytes(co->outdir);
    char path[PATH_MAX + 32];
    snprintf(path, sizeof path, "%s/summary.json", co->outdir);
    int fd = -1, rc = avail >= 0.0 && avail < need ? ENOSPC : 0;
    if (!rc) {
        fd = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
        static const char head[] = "{\"status\": \"running\", \"message\": \"the run has not ended, or lahar was "
                                   "killed before it could write this summary\"}\n";
        char *buf = fd >= 0 ? malloc(COORD_SUMMARY_RESERVE) : NULL;
        if (buf) {
            memset(buf, ' ', COORD_SUMMARY_RESERVE);
            memcpy(buf, head, sizeof head - 1);
            buf[COORD_SUMMARY_RESERVE - 1] = '\n';
        }
        /* the blocks are allocated now (posix_fallocate), not at some later write-back */
        if (fd < 0 || !buf)
            rc = errno ? errno : ENOMEM;
        else if ((rc = posix_fallocate(fd, 0, COORD_SUMMARY_RESERVE)) == 0 &&
                 pwrite(fd, buf, COORD_SUMMARY_RESERVE, 0) != COORD_SUMMARY_RESERVE)
            rc = errno ? errno : EIO;
        free(buf);
    }
    if (rc) {
        if (fd >= 0) {
            close(fd);
            unlink(path);
        }
        if (rc == ENOSPC)
            fprintf(stderr, "lahar: %s: no space left on device (%.0f bytes free; this run needs at least %.0f for "
                            "its first snapshots and summary.json); free space there or choose another -o\n",
                    co->outdir, avail, need);
        else
            fprintf(stderr, "lahar: cannot write %s: %s; choose another -o\n", path, strerror(rc));
        return -1;
    }
    co->summary_fd = fd;
    return 0;
}

/* OUT created, its absolute path (the nodes write there from their own working directories) and
 * its lock; the lock's descriptor, or -1 after saying why. */
int coord_claim_outdir(coord *co)
{
    if (lahar_mkdir_p(co->o->outdir) != 0 || !realpath(co->o->outdir, co->outdir)) {
        fprintf(stderr, "lahar: cannot create the output directory %s: %s\n", co->o->outdir, strerror(errno));
        return -1;
    }
    return coord_lock_outdir(co->outdir, co->c->path);
}

/* What OUT holds before the nodes start: for `lahar resume` the output cut back to the newest
 * checkpoint and the case it continues (co->c becomes that copy, with the resume fields); for a
 * new run an OUT without an earlier run's files, and the case kept beside the checkpoints.
 * COORD_GO_ON, or the exit status (LAHAR_EXIT_OK: a resume with nothing left to do). */
int coord_prepare_outdir(coord *co)
{
    static lahar_case resumed_case; /* the case with the resume fields (and a later end) */
    if (co->o->resume) {
        resumed_case = *co->c;
        int rc = coord_resume_prepare(co, &resumed_case, co->o->resume_t_end);
        if (rc != 0)
            return rc > 0 ? LAHAR_EXIT_OK : LAHAR_EXIT_SETUP;
        co->c = &resumed_case;
        return COORD_GO_ON;
    }
    if (coord_clear_outdir(co->outdir, co->o->overwrite) != 0 ||
        (co->ckpt_on && coord_save_case(co->outdir, co->c) != 0))
        return LAHAR_EXIT_SETUP;
    return COORD_GO_ON;
}
