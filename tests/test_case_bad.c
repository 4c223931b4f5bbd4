/* Bad-input test: every tests/bad_cases/<name>.yaml holds one class of mistake and says what the
 * loader must report in its first lines:
 *     # expect: bodies[0].radius: must be > 0
 *     # line: 12
 * The fixture is run through lahar-case-check, which must exit with status 2 and print exactly
 * one line on stderr that starts with `<fixture path>:<line>:` and contains every expected
 * fragment (one `# expect:` line each, up to 4). Under the sanitizer build a leak on the error
 * path changes the exit status, so this also checks that nothing stays allocated on failure.
 * A fixture that needs an input file of HDF5 says so in a header line
 *     # h5: NAME DATASET N [VALUE]
 * and is run from a copy in SCRATCH_DIR beside a file NAME holding DATASET of N doubles, written
 * here (inputs are made by the test, not kept in the source tree): 0, 1, 2, ..., or N times VALUE
 * (read by strtod: nan and inf too). */
#include <dirent.h>
#include <hdf5.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

/* dir/name with one dataset of n doubles (0, 1, 2, ..., or all `fill` when it is not ""). 0 or -1. */
static int write_h5_input(const char *dir, const char *name, const char *dataset, int n, const char *fill)
{
    char path[2048];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    hid_t f = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (f < 0)
        return -1;
    hsize_t dims = (hsize_t)n;
    hid_t sp = H5Screate_simple(1, &dims, NULL);
    hid_t ds = H5Dcreate2(f, dataset, H5T_IEEE_F64LE, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    double *v = calloc((size_t)(n > 0 ? n : 1), sizeof *v);
    for (int i = 0; v && i < n; i++)
        v[i] = fill[0] ? strtod(fill, NULL) : (double)i;
    int rc = ds >= 0 && v && H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) >= 0 ? 0 : -1;
    free(v);
    if (ds >= 0)
        H5Dclose(ds);
    H5Sclose(sp);
    H5Fclose(f);
    return rc;
}

/* Copy src to dir/name. 0 or -1. */
static int copy_file(const char *src, const char *dir, const char *name)
{
    char path[2048], buf[8192];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *in = fopen(src, "rb"), *out = in ? fopen(path, "wb") : NULL;
    int rc = in && out ? 0 : -1;
    size_t k;
    while (!rc && (k = fread(buf, 1, sizeof buf, in)) > 0)
        if (fwrite(buf, 1, k, out) != k)
            rc = -1;
    if (in)
        fclose(in);
    if (out && fclose(out) != 0)
        rc = -1;
    return rc;
}

static int name_cmp(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

/* Run prog with arg; stderr into buf. Returns the exit status (or -1). */
static int run_capture(const char *prog, const char *arg, char *buf, size_t n)
{
    int fd[2];
    if (pipe(fd) != 0)
        return -1;
    pid_t pid = fork();
    if (pid < 0)
        return -1;
    if (pid == 0) {
        dup2(fd[1], 2);
        close(fd[0]);
        close(fd[1]);
        execl(prog, prog, arg, (char *)NULL);
        _exit(127);
    }
    close(fd[1]);
    size_t k = 0;
    ssize_t got;
    while ((got = read(fd[0], buf + k, n - 1 - k)) > 0 && k + 1 < n)
        k += (size_t)got;
    buf[k] = '\0';
    close(fd[0]);
    int st = 0;
    if (waitpid(pid, &st, 0) < 0)
        return -1;
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

int main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: %s LAHAR_CASE_CHECK BAD_CASES_DIR SCRATCH_DIR\n", argv[0]);
        return 1;
    }
    DIR *d = opendir(argv[2]);
    if (!d) {
        perror(argv[2]);
        return 1;
    }
    char *names[512];
    int n = 0;
    struct dirent *de;
    while ((de = readdir(d)) && n < 512) {
        size_t l = strlen(de->d_name);
        if (l > 5 && strcmp(de->d_name + l - 5, ".yaml") == 0)
            names[n++] = strdup(de->d_name);
    }
    closedir(d);
    qsort(names, (size_t)n, sizeof *names, name_cmp);
    int failures = 0;
    for (int i = 0; i < n; i++) {
        char path[2048], expect[4][1100] = {"", "", "", ""}, line[1100] = "", buf[8192], want[4200];
        char h5name[256] = "", h5set[256] = "", h5fill[64] = "";
        int nexpect = 0, h5n = -1;
        snprintf(path, sizeof path, "%s/%s", argv[2], names[i]);
        FILE *fp = fopen(path, "r");
        if (!fp) {
            perror(path);
            failures++;
            continue;
        }
        char l[1024];
        while (fgets(l, sizeof l, fp) && l[0] == '#') {
            l[strcspn(l, "\n")] = '\0';
            if (strncmp(l, "# expect: ", 10) == 0 && nexpect < 4)
                snprintf(expect[nexpect++], sizeof expect[0], "%.1000s", l + 10);
            else if (strncmp(l, "# line: ", 8) == 0)
                snprintf(line, sizeof line, "%.1000s", l + 8);
            else if (strncmp(l, "# h5: ", 6) == 0 && sscanf(l + 6, "%255s %255s %d %63s", h5name, h5set, &h5n, h5fill) < 3)
                h5n = -1;
        }
        fclose(fp);
        if (h5n >= 0) { /* run it from a copy beside its generated input */
            if (copy_file(path, argv[3], names[i]) != 0 || write_h5_input(argv[3], h5name, h5set, h5n, h5fill) != 0) {
                printf("FAIL %s: cannot make its input %s/%s\n", names[i], argv[3], h5name);
                failures++;
                continue;
            }
            snprintf(path, sizeof path, "%s/%s", argv[3], names[i]);
        }
        if (!nexpect || !line[0]) {
            printf("FAIL %s: fixture lacks '# expect:' or '# line:' header\n", names[i]);
            failures++;
            continue;
        }
        int st = run_capture(argv[1], path, buf, sizeof buf);
        snprintf(want, sizeof want, "%s:%s: ", path, line);
        int one_line = strchr(buf, '\n') == buf + strlen(buf) - 1, found = 1;
        for (int e = 0; e < nexpect; e++)
            found &= strstr(buf, expect[e]) != NULL;
        const char *why = st != 2 ? "exit status is not 2"
                          : strncmp(buf, want, strlen(want)) != 0 ? "message does not start with <path>:<line>:"
                          : !found ? "an expected fragment is missing"
                          : !one_line ? "not exactly one line on stderr" : NULL;
        if (why) {
            printf("FAIL %s: %s (status %d)\n  want: %s... %s\n  got:  %s\n", names[i], why, st, want, expect[0], buf);
            failures++;
        } else {
            printf("ok   %s\n     %s", names[i], buf);
        }
    }
    for (int i = 0; i < n; i++)
        free(names[i]);
    if (n < 20) {
        printf("FAIL: only %d fixtures found in %s (expected one per error class, >= 20)\n", n, argv[2]);
        failures++;
    }
    printf("%d fixtures, %d failures\n", n, failures);
    return failures ? 1 : 0;
}
