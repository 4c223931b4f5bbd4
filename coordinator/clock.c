/* The coordinator's clock: times from integers and exactly known quantities only.
 *
 * Output times are T_j = j * output_interval (j an integer; T_nout = t_end, or nout * output_interval
 * when t_end is that multiple up to round-off). Between two output
 * times the coordinator takes m equal steps h = (T_{j+1} - t_b) / m from a segment start t_b,
 * so t_k = t_b + i * h (i = steps since t_b) and the last step of the segment ends exactly at
 * T_{j+1}, which is assigned, not summed. t_b is T_j, or the time t_b + i * h at which the
 * nodes' proposals forced a smaller step (or allowed a clearly larger one) inside the interval;
 * rounding therefore never accumulates over more than one output interval and output times are
 * hit exactly. */
#include <math.h>
#include "coordinator.h"

void lahar_clock_init(lahar_clock *c, double t_end, double out_interval)
{
    c->t_end = t_end;
    c->out_interval = out_interval > 0.0 && out_interval < t_end ? out_interval : t_end;
    c->nout = (int64_t)ceil(t_end / c->out_interval - 1e-9);
    if (c->nout < 1)
        c->nout = 1;
    c->j = 0;
    c->t_base = 0.0;
    c->h = 0.0;
    c->i = 0;
    c->m = 0;
}

double lahar_clock_output_time(const lahar_clock *c, int64_t j)
{
    if (j < c->nout)
        return (double)j * c->out_interval;
    /* The end. When t_end is a multiple of the interval up to round-off (0.15 = 3 x 0.05 is not
     * exact in binary), it is that grid time, the same double a longer run passes on its way:
     * a run extended by `lahar resume --time-end` then continues from exactly where the longer
     * run would be, bit for bit. */
    double grid = (double)c->nout * c->out_interval;
    return fabs(grid - c->t_end) <= 1e-9 * c->t_end ? grid : c->t_end;
}

int lahar_clock_next(lahar_clock *c, double dt_allowed, double *t, double *t_next, int *is_output)
{
    if (c->j >= c->nout)
        return 1;
    double target = lahar_clock_output_time(c, c->j + 1);
    double t_cur = c->i == 0 ? c->t_base : c->t_base + (double)c->i * c->h;
    /* steps needed from here at the allowed size (the 1e-9 absorbs round-off in the ratio) */
    double ratio = (target - t_cur) / dt_allowed;
    int64_t need = (int64_t)ceil(ratio - 1e-9);
    if (need < 1)
        need = 1;
    int64_t left = c->m - c->i;
    if (c->m == 0 || dt_allowed < c->h * (1.0 - 1e-12) || left > need + need / 4 + 1) {
        c->t_base = t_cur;
        c->i = 0;
        c->m = need;
        c->h = (target - t_cur) / (double)need;
    }
    *t = t_cur;
    *is_output = c->i + 1 == c->m;
    *t_next = *is_output ? target : c->t_base + (double)(c->i + 1) * c->h;
    return 0;
}

void lahar_clock_advance(lahar_clock *c)
{
    if (++c->i == c->m) {
        c->j++;
        c->t_base = lahar_clock_output_time(c, c->j);
        c->i = 0;
        c->m = 0;
    }
}
