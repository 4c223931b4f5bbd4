/* The coordinator's clock (coordinator/clock.c): output times are hit exactly (bitwise equal to
 * j * output_interval), every step respects the allowed dt, the number of steps per interval is
 * the minimum ceil(interval / dt), and the time never drifts over a long run with changing dt. */
#include <math.h>
#include <stdio.h>
#include "coordinator.h"

#include "test_util.h"

/* Run a whole simulation; dt_of(k) gives the allowed dt of step k. Returns steps taken. */
static long run(double t_end, double out, double (*dt_of)(long), long *outputs_hit)
{
    lahar_clock c;
    lahar_clock_init(&c, t_end, out);
    double t_prev = 0.0;
    long k = 0, hits = 0;
    double t, tn;
    int is_out;
    while (!lahar_clock_next(&c, dt_of(k), &t, &tn, &is_out)) {
        CHECK(t == t_prev, "step %ld starts at %.17g, previous ended at %.17g", k, t, t_prev);
        CHECK(tn > t, "step %ld does not advance", k);
        CHECK(tn - t <= dt_of(k) * (1.0 + 1e-12), "step %ld: dt %.17g > allowed %.17g", k, tn - t, dt_of(k));
        if (is_out) {
            hits++;
            double expect = hits >= c.nout ? t_end : (double)hits * out;
            CHECK(tn == expect, "output %ld at %.17g, expected exactly %.17g", hits, tn, expect);
        }
        lahar_clock_advance(&c);
        t_prev = tn;
        k++;
        if (failures > 10)
            break;
    }
    CHECK(t_prev == t_end, "run ends at %.17g, expected exactly %.17g", t_prev, t_end);
    *outputs_hit = hits;
    return k;
}

static double dt_const(long k) { (void)k; return 1e-3; }
static double dt_awkward(long k) { (void)k; return 0.0007; }
/* proposals that shrink and grow like an SPH node's CFL limit */
static double dt_wavy(long k) { return 1e-4 * (1.5 + sin(0.001 * (double)k)); }

int main(void)
{
    long hits;
    /* 1 s at dt 1e-3, outputs every 0.05 s: 1000 steps, 20 outputs */
    long n = run(1.0, 0.05, dt_const, &hits);
    CHECK(n == 1000, "constant dt: %ld steps, expected 1000", n);
    CHECK(hits == 20, "constant dt: %ld outputs, expected 20", hits);
    /* dt that does not divide the interval: ceil(0.05 / 0.0007) = 72 steps per interval */
    n = run(1.0, 0.05, dt_awkward, &hits);
    CHECK(n == 20 * 72, "awkward dt: %ld steps, expected %d", n, 20 * 72);
    /* t_end not a multiple of the interval: last output at t_end */
    n = run(0.33, 0.1, dt_const, &hits);
    CHECK(hits == 4, "t_end 0.33 / 0.1: %ld outputs, expected 4", hits);
    CHECK(n == 330, "t_end 0.33: %ld steps, expected 330", n);
    /* a long run with a changing limit: no drift (checked inside run) and close to the minimum
     * number of steps (integral of 1/dt), within 2 % */
    n = run(20.0, 0.01, dt_wavy, &hits);
    double tsum = 0.0;
    long steps_min = 0;
    while (tsum < 20.0) {
        tsum += dt_wavy(steps_min);
        steps_min++;
    }
    double ideal = (double)steps_min; /* plus at most one rounding step per output interval */
    CHECK(hits == 2000, "wavy dt: %ld outputs, expected 2000", hits);
    CHECK((double)n <= ideal * 1.02 + 2000, "wavy dt: %ld steps, about %g needed", n, ideal);
    printf("clock: %ld steps for 20 s with a varying limit (greedy minimum %.0f)\n", n, ideal);
    if (failures)
        return 1;
    printf("PASS test_coupling_clock\n");
    return 0;
}
