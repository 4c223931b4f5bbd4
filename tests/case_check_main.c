/* lahar-case-check CASE.yaml: load and validate a case file, nothing else. Exits 0 when the case
 * is valid, 2 with one `file:line: key: problem; fix` message on stderr when it is not. Used by
 * the bad-input tests (tests/bad_cases) and handy to check a case before a long run. */
#include <stdint.h>
#include <stdio.h>
#include "case.h"

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s CASE.yaml\n", argv[0]);
        return LAHAR_EXIT_BAD_INPUT;
    }
    lahar_case c;
    int rc = lahar_case_load(argv[1], &c);
    if (rc == 0) {
        int64_t np = 0;
        for (int i = 0; i < c.nblock; i++)
            np += lahar_case_block_lattice(&c, i, NULL, 0);
        printf("%s: ok (%dD, %d materials, %d bodies, %d particle blocks", argv[1], c.dim, c.nmaterial, c.nbody,
               c.nblock);
        if (c.nblock > 0)
            printf(", %lld particles, c0 = %g m/s", (long long)np, c.sph.c0);
        printf(")\n");
        lahar_case_free(&c);
    }
    return rc;
}
