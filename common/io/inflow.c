/* Inflow hydrographs and their CSV reader (declared in common/scene/inflow.h). */
#include "inflow.h"
#include "errmsg.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* linear in a table (t increasing), the end values outside */
static double table_at(const double *tt, const double *vv, int n, double t)
{
    if (n <= 0)
        return 0.0;
    if (t <= tt[0])
        return vv[0];
    if (t >= tt[n - 1])
        return vv[n - 1];
    int lo = 0, hi = n - 1; /* tt[lo] < t < tt[hi] */
    while (hi - lo > 1) {
        const int mid = (lo + hi) / 2;
        if (tt[mid] <= t)
            lo = mid;
        else
            hi = mid;
    }
    const double w = (t - tt[lo]) / (tt[hi] - tt[lo]);
    return vv[lo] + w * (vv[hi] - vv[lo]);
}

double lahar_inlet_hydrograph(const lahar_inlet *in, double t)
{
    if (!(t >= in->t_start && t < in->t_end))
        return 0.0;
    switch (in->kind) {
    case LAHAR_HYDRO_GUMBEL: {
        /* Trujillo-Vela et al. 2020, eq. 36 */
        const double a = in->gumbel[0], beta = in->gumbel[1], mu = in->gumbel[2];
        const double e = exp(-(t - mu) / beta);
        return a / beta * e * exp(-e);
    }
    case LAHAR_HYDRO_TABLE_U:
    case LAHAR_HYDRO_TABLE_Q:
        return table_at(in->table_t, in->table_v, in->ntable, t);
    default:
        return in->velocity;
    }
}

double lahar_inlet_level(const lahar_inlet *in, double t)
{
    return in->nlevel > 0 ? table_at(in->level_t, in->level_h, in->nlevel, t) : in->level;
}

/* the first two comma-separated fields of a line as numbers; 0 or -1 */
static int csv_pair(char *s, double out[2])
{
    for (int k = 0; k < 2; k++) {
        while (*s == ' ' || *s == '\t')
            s++;
        char *end = NULL;
        errno = 0;
        out[k] = strtod(s, &end);
        if (end == s || errno == ERANGE || !isfinite(out[k]))
            return -1;
        s = end;
        while (*s == ' ' || *s == '\t')
            s++;
        if (k == 0) {
            if (*s != ',')
                return -1;
            s++;
        }
    }
    return *s == '\0' || *s == '\n' || *s == '\r' ? 0 : -1;
}

int lahar_hydrograph_read_csv(const char *path, int *kind, double **t, double **v, char *err, int errlen)
{
    *t = *v = NULL;
    FILE *f = lahar_fopen_input(path, "r");
    if (!f) {
        snprintf(err, (size_t)errlen, "cannot open the hydrograph %s (%s); give a CSV file with a header line "
                 "`t,u` or `t,Q`", path, strerror(errno));
        return -1;
    }
    char line[512];
    int lineno = 0, n = 0, cap = 0, header = 0;
    while (fgets(line, sizeof line, f)) {
        lineno++;
        char *s = line;
        while (*s == ' ' || *s == '\t')
            s++;
        if (*s == '#' || *s == '\n' || *s == '\r' || *s == '\0')
            continue;
        if (!header) {
            char a[32], b[32];
            if (sscanf(s, " %31[^, \t] , %31[^, \t\r\n]", a, b) != 2 || strcmp(a, "t") != 0 ||
                (strcmp(b, "u") != 0 && strcmp(b, "Q") != 0 && strcmp(b, "h") != 0)) {
                snprintf(err, (size_t)errlen, "%s:%d: the first line must be the header `t,u` (velocity, m/s), "
                         "`t,Q` (discharge) or `t,h` (level, m)", path, lineno);
                goto fail;
            }
            *kind = b[0] == 'u' ? LAHAR_HYDRO_TABLE_U : b[0] == 'Q' ? LAHAR_HYDRO_TABLE_Q : LAHAR_HYDRO_TABLE_H;
            header = 1;
            continue;
        }
        double pv[2];
        if (csv_pair(s, pv) != 0) {
            s[strcspn(s, "\r\n")] = '\0'; /* the message is one line */
            snprintf(err, (size_t)errlen, "%s:%d: expected two finite numbers `t,value` separated by a comma, got "
                     "'%.40s'", path, lineno, s);
            goto fail;
        }
        if (n > 0 && !(pv[0] > (*t)[n - 1])) {
            snprintf(err, (size_t)errlen, "%s:%d: t = %g does not increase (the row before has t = %g); sort the "
                     "rows by time", path, lineno, pv[0], (*t)[n - 1]);
            goto fail;
        }
        if (n == cap) {
            cap = cap ? 2 * cap : 64;
            double *nt = realloc(*t, (size_t)cap * sizeof *nt);
            if (nt)
                *t = nt;
            double *nv = nt ? realloc(*v, (size_t)cap * sizeof *nv) : NULL;
            if (nv)
                *v = nv;
            if (!nt || !nv) {
                snprintf(err, (size_t)errlen, "%s: out of memory", path);
                goto fail;
            }
        }
        (*t)[n] = pv[0], (*v)[n] = pv[1];
        n++;
    }
    fclose(f);
    if (n == 0) {
        snprintf(err, (size_t)errlen, "%s: no rows after the header; add rows `t,value`", path);
        free(*t), free(*v);
        *t = *v = NULL;
        return -1;
    }
    return n;
fail:
    fclose(f);
    free(*t), free(*v);
    *t = *v = NULL;
    return -1;
}
