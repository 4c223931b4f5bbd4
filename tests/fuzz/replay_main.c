/* Replays files through a fuzz harness without libFuzzer (any compiler): each argument is a file
 * or a directory whose regular files are fed in name order. Exit 0 when every input went through
 * (a crash or a sanitizer report ends the process first), 2 on a missing path. */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include "fuzz.h"

static int replay_file(const char *path)
{
    size_t n = 0;
    uint8_t *exact = fuzz_read_file(path, &n);
    if (!exact)
        return -1;
    LLVMFuzzerTestOneInput(exact, n);
    free(exact);
    return 0;
}

static int name_cmp(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

int main(int argc, char **argv)
{
    long count = 0;
    for (int i = 1; i < argc; i++) {
        struct stat st;
        if (stat(argv[i], &st) != 0) {
            fprintf(stderr, "%s: no such file or directory\n", argv[i]);
            return 2;
        }
        if (!S_ISDIR(st.st_mode)) {
            if (replay_file(argv[i]) != 0) {
                fprintf(stderr, "%s: cannot read\n", argv[i]);
                return 2;
            }
            count++;
            continue;
        }
        struct dirent **list;
        int n = scandir(argv[i], &list, NULL, NULL);
        if (n < 0) {
            fprintf(stderr, "%s: cannot list\n", argv[i]);
            return 2;
        }
        char **names = malloc(sizeof *names * (size_t)(n ? n : 1));
        for (int j = 0; j < n; j++)
            names[j] = list[j]->d_name;
        qsort(names, (size_t)n, sizeof *names, name_cmp);
        for (int j = 0; j < n; j++) {
            char path[4096];
            snprintf(path, sizeof path, "%s/%s", argv[i], names[j]);
            if (stat(path, &st) == 0 && S_ISREG(st.st_mode) && names[j][0] != '.') {
                if (replay_file(path) != 0) {
                    fprintf(stderr, "%s: cannot read\n", path);
                    return 2;
                }
                count++;
            }
        }
        for (int j = 0; j < n; j++)
            free(list[j]);
        free(list);
        free(names);
    }
    printf("replayed %ld inputs\n", count);
    return 0;
}
