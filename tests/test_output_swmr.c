/* The force stream is readable while it grows: a child process appends one row every 50 ms for
 * 2 s through lahar_body_output_forces; the parent opens OUT/forces.h5 with H5F_ACC_SWMR_READ,
 * refreshes /t and must see the row count grow at least twice before the writer ends, never
 * more than 0.5 s (the flush period) + 0.25 s (scheduling margin) behind the writer, with the
 * right values.
 *   test_output_swmr OUTDIR            writer child + C reader (the test)
 *   test_output_swmr --writer OUTDIR   only the writer (tests/test_output_swmr_h5py.py reads) */
#include <errno.h>
#include <hdf5.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include "output.h"
#include "shape_build.h"

#define NROW 40
#define ROW_PERIOD 0.05

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void sleep_until(double t)
{
    double d = t - now();
    if (d > 0) {
        struct timespec ts = {(time_t)d, (long)((d - floor(d)) * 1e9)};
        while (nanosleep(&ts, &ts) < 0 && errno == EINTR)
            ;
    }
}

static int writer(const char *dir, double t0)
{
    lahar_material mat = {.name = "rock", .density = 2650, .restitution = 0.5, .friction = 0.5};
    lahar_body b[2];
    memset(b, 0, sizeof b);
    snprintf(b[0].name, sizeof b[0].name, "ball");
    snprintf(b[1].name, sizeof b[1].name, "floor");
    double c[3] = {0, 0, 0}, n[3] = {0, 0, 1}, size[2] = {1, 1};
    lahar_shape_make_sphere(&b[0].shape, 0.05);
    lahar_shape_make_plane(&b[1].shape, c, n, size, 0.001);
    b[0].q[0] = b[1].q[0] = 1.0;
    b[0].mass = 1.0;
    b[1].motion = LAHAR_MOTION_FIXED;
    lahar_case cs = {.dim = 3, .nmaterial = 1, .materials = &mat, .nbody = 2, .bodies = b, .output_forces = 1};
    char err[512];
    lahar_body_output *o = lahar_body_output_open(dir, &cs, err, sizeof err);
    if (!o) {
        fprintf(stderr, "writer: %s\n", err);
        return 1;
    }
    for (int k = 0; k < NROW; k++) {
        sleep_until(t0 + k * ROW_PERIOD);
        lahar_body_report r[2];
        memset(r, 0, sizeof r);
        r[0].force[2] = -9.81 * k;
        r[1].force[2] = 9.81 * k;
        r[1].ncontacts = 1;
        if (lahar_body_output_forces(o, k, k * 1e-3, r))
            return 1;
    }
    lahar_body_output_close(o);
    lahar_shape_free(&b[0].shape);
    lahar_shape_free(&b[1].shape);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "--writer") == 0) {
        mkdir(argv[2], 0755);
        return writer(argv[2], now() + 0.2);
    }
    const char *dir = argc > 1 ? argv[1] : "test_output_swmr_dir";
    mkdir(dir, 0755);
    char path[1200];
    snprintf(path, sizeof path, "%s/forces.h5", dir);
    unlink(path);
    double t0 = now() + 0.3;
    /* fork before the parent touches HDF5, so the child starts with a fresh library */
    pid_t pid = fork();
    if (pid == 0)
        _exit(writer(dir, t0));
    hid_t f = H5I_INVALID_HID;
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL); /* opening fails quietly until the writer made it */
    while (now() < t0 + 5.0) {
        if (access(path, R_OK) == 0 && (f = H5Fopen(path, H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, H5P_DEFAULT)) >= 0)
            break;
        usleep(20000);
    }
    int failures = 0;
    if (f < 0) {
        fprintf(stderr, "FAIL: could not open %s with SWMR read\n", path);
        kill(pid, SIGKILL);
        waitpid(pid, NULL, 0);
        return 1;
    }
    hid_t ds = H5Dopen2(f, "t", H5P_DEFAULT), dsf = H5Dopen2(f, "force", H5P_DEFAULT);
    int growth = 0, status = 0, done = 0;
    hsize_t last = 0;
    while (!done) {
        done = waitpid(pid, &status, WNOHANG) == pid;
        H5Drefresh(ds);
        hsize_t nrow = 0;
        hid_t sp = H5Dget_space(ds);
        H5Sget_simple_extent_dims(sp, &nrow, NULL);
        H5Sclose(sp);
        /* rows the writer had produced 0.5 s + margin ago must be visible now */
        double tau = now() - t0;
        int must = (int)floor((tau - 0.5 - 0.25) / ROW_PERIOD) + 1;
        if (must > NROW)
            must = NROW;
        if (!done && (int)nrow < must) {
            fprintf(stderr, "FAIL: at %.2f s the reader sees %d rows, at least %d were due\n", tau, (int)nrow, must);
            failures++;
        }
        if (nrow > last) {
            if (!done)
                growth++;
            double *t = malloc(nrow * sizeof *t);
            H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, t);
            for (hsize_t k = 0; k < nrow; k++)
                if (t[k] != (double)k * 1e-3) {
                    fprintf(stderr, "FAIL: t[%d] = %g\n", (int)k, t[k]);
                    failures++;
                    break;
                }
            free(t);
            last = nrow;
        }
        usleep(30000);
    }
    /* after the writer closed: everything, and the force rows match */
    H5Drefresh(dsf);
    hsize_t d3[3] = {0, 0, 0};
    hid_t sp = H5Dget_space(dsf);
    H5Sget_simple_extent_dims(sp, d3, NULL);
    H5Sclose(sp);
    if (d3[0] != NROW || d3[1] != 2 || d3[2] != 3) {
        fprintf(stderr, "FAIL: force shape %d x %d x %d\n", (int)d3[0], (int)d3[1], (int)d3[2]);
        failures++;
    } else {
        double *fr = malloc(sizeof *fr * NROW * 6);
        H5Dread(dsf, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, fr);
        if (fr[(NROW - 1) * 6 + 5] != 9.81 * (NROW - 1)) {
            fprintf(stderr, "FAIL: last floor force %g\n", fr[(NROW - 1) * 6 + 5]);
            failures++;
        }
        free(fr);
    }
    H5Dclose(ds), H5Dclose(dsf), H5Fclose(f);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        fprintf(stderr, "FAIL: writer exited with status %d\n", status);
        failures++;
    }
    if (growth < 2) {
        fprintf(stderr, "FAIL: the reader saw the dataset grow only %d times while the writer ran\n", growth);
        failures++;
    }
    printf("test_output_swmr: saw %d increments while writing, never more than 0.75 s behind: %s\n", growth,
           failures ? "FAIL" : "ok");
    return failures ? 1 : 0;
}
