/* Instability reports through a STATUS message (common/protocol/instability.h): what a node encodes, the
 * coordinator decodes field for field, within the 512 bytes of status_t.message; a '|' in a body
 * name cannot shift the fields; an ordinary error message is not taken for an instability. */
#include <math.h>
#include <string.h>
#include "instability.h"
#include "test_util.h"

int main(void)
{
    lahar_instability u;
    memset(&u, 0, sizeof u);
    snprintf(u.what, sizeof u.what, "overlap");
    snprintf(u.kind, sizeof u.kind, "body");
    u.id = 3;
    snprintf(u.name, sizeof u.name, "rock|big");
    u.x[0] = 0.125, u.x[1] = -2.5e-3, u.x[2] = 1.0 / 3.0;
    u.step = 123456789012LL;
    u.t = 0.1 + 0.2;
    u.value = 2.75e-3;
    u.limit = 2.5e-3;
    memset(u.text, 'x', sizeof u.text - 1); /* longer than what fits: cut, not overflowing */
    char msg[512];
    lahar_instability_encode(&u, msg, sizeof msg);
    CHECK(strlen(msg) < sizeof msg, "message not terminated within 512 bytes");
    lahar_instability v;
    CHECK(lahar_instability_decode(msg, &v) == 1, "not recognised: %s", msg);
    CHECK(!strcmp(v.what, "overlap") && !strcmp(v.kind, "body") && v.id == 3, "what/kind/id: %s %s %lld", v.what,
          v.kind, (long long)v.id);
    CHECK(!strcmp(v.name, "rock/big"), "a '|' in the name must not split fields: '%s'", v.name);
    for (int a = 0; a < 3; a++)
        CHECK(fabs(v.x[a] - u.x[a]) <= 1e-8 * fabs(u.x[a]), "x[%d] %.17g vs %.17g", a, v.x[a], u.x[a]);
    CHECK(v.step == u.step && fabs(v.t - u.t) <= 1e-11 * u.t, "step/time %lld %.17g", (long long)v.step, v.t);
    CHECK(fabs(v.value - u.value) <= 1e-5 * u.value && fabs(v.limit - u.limit) <= 1e-5 * u.limit, "value/limit");
    CHECK(strlen(v.text) > 100 && v.text[0] == 'x', "text lost: '%.20s'", v.text);

    /* NaN position and value (a non-finite state) survive as NaN */
    u.x[0] = u.value = NAN;
    snprintf(u.text, sizeof u.text, "particle 7 has a non-finite state");
    lahar_instability_encode(&u, msg, sizeof msg);
    CHECK(lahar_instability_decode(msg, &v) == 1 && isnan(v.x[0]) && isnan(v.value) &&
              !strcmp(v.text, "particle 7 has a non-finite state"),
          "NaN fields: %s", msg);

    /* plain errors are not instabilities */
    memset(&v, 0, sizeof v);
    CHECK(lahar_instability_decode("cannot write a particle snapshot in /x", &v) == 0 && v.what[0] == 0,
          "a plain error decoded as an instability");
    CHECK(lahar_instability_decode("UNSTABLE|overlap|body", &v) == 0, "a truncated report decoded");
    if (!failures)
        printf("instability reports: encode/decode exact within 512 bytes, '|' in names escaped\n");
    return failures != 0;
}
