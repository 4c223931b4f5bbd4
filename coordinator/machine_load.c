/* How busy the machine is when a run starts (machine_load.h). */
#define _GNU_SOURCE
#include "machine_load.h"
#include <ctype.h>
#include <dirent.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* 1 when /proc/PID/cmdline is `lahar run|check|resume ...` (the program's name, without its
 * directory, is lahar: not lahar-sph or lahar-dem, which a run starts) */
static int is_lahar_run(const char *pid)
{
    char path[300], cmd[512];
    snprintf(path, sizeof path, "/proc/%s/cmdline", pid);
    FILE *f = fopen(path, "r");
    if (!f)
        return 0;
    const size_t n = fread(cmd, 1, sizeof cmd - 1, f);
    fclose(f);
    cmd[n] = '\0';
    const size_t len0 = strlen(cmd);
    if (len0 + 1 >= n) /* no second argument (or a kernel thread: empty) */
        return 0;
    const char *slash = strrchr(cmd, '/');
    const char *prog = slash ? slash + 1 : cmd, *verb = cmd + len0 + 1;
    return strcmp(prog, "lahar") == 0 &&
           (strcmp(verb, "run") == 0 || strcmp(verb, "check") == 0 || strcmp(verb, "resume") == 0);
}

/* The other lahar runs on the machine, or 0 when /proc cannot be read */
static int other_lahar_runs(void)
{
    DIR *d = opendir("/proc");
    if (!d)
        return 0;
    char self[32];
    snprintf(self, sizeof self, "%ld", (long)getpid());
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (isdigit((unsigned char)e->d_name[0]) && strcmp(e->d_name, self) != 0)
            n += is_lahar_run(e->d_name);
    closedir(d);
    return n;
}

int lahar_machine_load_read(lahar_machine_load *m)
{
    cpu_set_t set;
    double load[1];
    m->busy_now = -1.0;
    m->other_runs = other_lahar_runs();
    if (sched_getaffinity(0, sizeof set, &set) != 0 || getloadavg(load, 1) != 1)
        return -1;
    m->cores = CPU_COUNT(&set);
    m->load1 = load[0];
    return m->cores > 0 ? 0 : -1;
}

/* /proc/stat: the ticks of all CPUs, busy (all but idle and iowait) and in total, and the number
 * of CPUs (its cpuN lines). Returns 0 or -1. */
static int proc_stat(unsigned long long *busy, unsigned long long *total, int *ncpu)
{
    FILE *f = fopen("/proc/stat", "r");
    if (!f)
        return -1;
    char line[512];
    unsigned long long v[8] = {0};
    int ok = fgets(line, sizeof line, f) &&
             sscanf(line, "cpu %llu %llu %llu %llu %llu %llu %llu %llu", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5],
                    &v[6], &v[7]) >= 5;
    *ncpu = 0;
    while (ok && fgets(line, sizeof line, f))
        *ncpu += strncmp(line, "cpu", 3) == 0;
    fclose(f);
    *total = 0;
    for (int i = 0; i < 8; i++)
        *total += v[i];
    *busy = *total - v[3] - v[4]; /* idle, iowait */
    return ok && *ncpu > 0 ? 0 : -1;
}

int lahar_machine_sample(lahar_machine_load *m, double seconds)
{
    unsigned long long b0, t0, b1, t1;
    int n0, n1;
    if (proc_stat(&b0, &t0, &n0) != 0)
        return -1;
    struct timespec ts = {(time_t)seconds, (long)((seconds - (double)(time_t)seconds) * 1e9)};
    nanosleep(&ts, NULL);
    if (proc_stat(&b1, &t1, &n1) != 0 || n1 != n0 || t1 <= t0)
        return -1;
    m->busy_now = (double)(b1 - b0) / (double)(t1 - t0) * n0;
    return 0;
}

int lahar_machine_threads(const lahar_machine_load *m, int threads)
{
    return threads > 0 ? threads : m->cores;
}

int lahar_machine_busy(const lahar_machine_load *m, int threads)
{
    const int t = lahar_machine_threads(m, threads);
    /* half a core of slack for short-lived tasks; the load average decays over a minute, so a run
     * started just after a build or another run reads its load: the sample tells whether it is
     * still there */
    if (t > 1 && m->other_runs > 0 && (double)(m->other_runs + 1) * t > m->cores + 0.5)
        return 1;
    return t > 1 && m->load1 + t > m->cores + 0.5 && (m->busy_now < 0.0 || m->busy_now + t > m->cores + 0.5);
}
