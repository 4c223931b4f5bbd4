/* Instability reports in STATUS messages (instability.h). */
#include "instability.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* '|' separates the fields: a name or a what that holds one is written with '/' instead */
static void inst_field(char *dst, size_t n, const char *src)
{
    snprintf(dst, n, "%s", src);
    for (char *p = dst; *p; p++)
        if (*p == '|' || *p == '\n')
            *p = '/';
}

void lahar_instability_encode(const lahar_instability *u, char *msg, size_t n)
{
    char what[sizeof u->what], kind[sizeof u->kind], name[sizeof u->name];
    inst_field(what, sizeof what, u->what);
    inst_field(kind, sizeof kind, u->kind);
    inst_field(name, sizeof name, u->name);
    snprintf(msg, n, LAHAR_INSTABILITY_PREFIX "%s|%s|%lld|%s|%.9g|%.9g|%.9g|%lld|%.12g|%.6g|%.6g|%s", what, kind,
             (long long)u->id, name, u->x[0], u->x[1], u->x[2], (long long)u->step, u->t, u->value, u->limit, u->text);
}

/* Copy the next '|'-terminated field of *s into dst (cut to n) and step past it; -1 at the end. */
static int inst_next(const char **s, char *dst, size_t n)
{
    const char *bar = strchr(*s, '|');
    if (!bar)
        return -1;
    size_t len = (size_t)(bar - *s);
    if (len >= n)
        len = n - 1;
    memcpy(dst, *s, len);
    dst[len] = '\0';
    *s = bar + 1;
    return 0;
}

int lahar_instability_decode(const char *msg, lahar_instability *u)
{
    size_t pl = strlen(LAHAR_INSTABILITY_PREFIX);
    if (!msg || strncmp(msg, LAHAR_INSTABILITY_PREFIX, pl) != 0)
        return 0;
    lahar_instability r;
    memset(&r, 0, sizeof r);
    const char *s = msg + pl;
    char num[11][64];
    if (inst_next(&s, r.what, sizeof r.what) || inst_next(&s, r.kind, sizeof r.kind) ||
        inst_next(&s, num[0], sizeof num[0]) || inst_next(&s, r.name, sizeof r.name))
        return 0;
    for (int i = 1; i < 8; i++)
        if (inst_next(&s, num[i], sizeof num[i]))
            return 0;
    r.id = strtoll(num[0], NULL, 10);
    for (int a = 0; a < 3; a++)
        r.x[a] = strtod(num[1 + a], NULL);
    r.step = strtoll(num[4], NULL, 10);
    r.t = strtod(num[5], NULL);
    r.value = strtod(num[6], NULL);
    r.limit = strtod(num[7], NULL);
    snprintf(r.text, sizeof r.text, "%s", s);
    *u = r;
    return 1;
}
