/* advance() allocates nothing in the steady state (dem_engine.h contract).
 *
 * This binary is linked with -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free, so
 * every call the engine (a static library linked into it) makes to these functions goes through
 * the counters below. The calls made inside libgomp (a shared library) are not seen; the engine
 * only creates its thread team, which libgomp keeps and reuses.
 *
 * Scenes, each stepped by coordinator steps of 1 ms (many substeps each):
 *  1. a settling pile of 120 mixed spheres, boxes and hull rocks in 2 layers (tests/bench/
 *     dem_pile.h) on a floor in a box: warm-up 0.3 s (both layers have landed), then 0.1 s
 *     counted: zero allocations, zero frees, with at least one contact per body throughout;
 *  2. one layer of 560 bodies on 2 threads: every body is paired with the floor, so there are
 *     >= 512 broad-phase pairs and the parallel narrow phase runs (warm-up 0.15 s on 1 thread,
 *     the layer has landed; restart into a 2-thread engine; 0.02 s counted);
 *  3. a restart read into a fresh engine followed by 20 steps: read_restart may size the arrays,
 *     the steps after it allocate nothing.
 * The warm-up allocations are printed too (allowed there: the arrays are pre-sized for about 4
 * contacts per body and double when a scene needs more). */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include "dem_pile.h"
#include "alloc_count.h"
#include "dem_test_util.h"

/* nsteps coordinator steps of 1 ms; returns the allocations + frees made inside advance. */
static long steps_counted(const lahar_dem_engine_ops *ops, lahar_dem_engine *e, int nsteps, long *nsub)
{
    char err[512];
    long before = alloc_nalloc + alloc_nfree;
    for (int k = 0; k < nsteps; k++) {
        alloc_counting = 1;
        int n = ops->advance(e, 1e-3, NULL, err, sizeof err);
        alloc_counting = 0;
        if (n < 0) {
            dem_test_check(0, "advance: %s", err);
            break;
        }
        *nsub += n;
    }
    return alloc_nalloc + alloc_nfree - before;
}

/* Engine of case c on `threads` threads continuing from the state of engine e (restart). */
static lahar_dem_engine *engine_moved(const lahar_case *c, const lahar_dem_engine_ops *ops, lahar_dem_engine *e,
                                      int threads)
{
    FILE *f = tmpfile();
    dem_test_check(f && ops->write_restart(e, f) == 0, "write_restart");
    rewind(f);
    omp_set_num_threads(threads);
    lahar_dem_engine *r = dem_test_engine(c, &ops);
    dem_test_check(ops->read_restart(r, f) == 0, "read_restart into an engine on %d thread(s)", threads);
    fclose(f);
    return r;
}

/* Warm-up on 1 thread (cheaper on a loaded machine), then count on `threads` threads after a
 * restart, and count again over 20 more steps. */
static void pile_check(int nbody, int layers, int threads, double warm, double meas)
{
    lahar_case c;
    dem_pile_case(&c, nbody, layers, 0, 4242u);
    omp_set_num_threads(1);
    const lahar_dem_engine_ops *ops;
    lahar_dem_engine *w = dem_test_engine(&c, &ops);
    long nsub = 0;
    long warm_calls = steps_counted(ops, w, (int)(warm * 1e3 + 0.5), &nsub);
    int c0 = ops->ncontacts(w);
    lahar_dem_engine *e = w;
    if (threads > 1) {
        e = engine_moved(&c, ops, w, threads);
        ops->destroy(w);
    }
    nsub = 0;
    long calls = steps_counted(ops, e, (int)(meas * 1e3 + 0.5), &nsub);
    int c1 = ops->ncontacts(e);
    dem_test_check(c0 >= nbody && c1 >= nbody,
                   "%d bodies: a real pile (%d contacts after the warm-up, %d at the end)", nbody, c0, c1);
    dem_test_check(calls == 0,
                   "%d bodies, %d thread(s): %ld malloc/calloc/realloc/free calls in %ld substeps after a %.2f s warm-up "
                   "(the warm-up made %ld)",
                   nbody, threads, calls, nsub, warm, warm_calls);
    if (threads == 1) { /* a restart into a fresh engine, then steps: nothing allocated after the read */
        lahar_dem_engine *r = engine_moved(&c, ops, e, 1);
        nsub = 0;
        calls = steps_counted(ops, r, 20, &nsub);
        dem_test_check(calls == 0, "after read_restart: %ld allocation calls in %ld substeps", calls, nsub);
        ops->destroy(r);
    }
    ops->destroy(e);
    dem_test_case_free(&c);
}

int main(void)
{
    /* the counters see this binary's calls: check that the wrapping is really in place */
    volatile size_t sz = 16; /* volatile: keep the compiler from eliding the pair */
    alloc_counting = 1;
    void *volatile p = malloc(sz);
    free(p);
    alloc_counting = 0;
    dem_test_check(alloc_nalloc == 1 && alloc_nfree == 1, "malloc/free are counted (--wrap works): %ld, %ld", alloc_nalloc, alloc_nfree);
    pile_check(120, 2, 1, 0.3, 0.1);
    pile_check(560, 1, 2, 0.15, 0.02);
    return dem_test_failures ? 1 : 0;
}
