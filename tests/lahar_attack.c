/* A hostile peer on a run's multicast group, for the authenticated-run test (coupling_runs.sh
 * cross_host_auth): for `seconds` it records the frames it hears on the LAHAR_* channels and,
 * 0.05 s after each (when the run has taken it), publishes three copies of it: altered (one byte of the header flipped,
 * the MAC kept), forged (the MAC zeroed) and replayed (verbatim). An authenticating link must
 * drop all of them and count the first two as rejected and the third as replayed.
 * usage: lahar_attack URL SECONDS   (prints how many frames it sent of each kind) */
#include <lcm/lcm.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAX_KEPT 4096
typedef struct {
    char channel[32];
    double t;
    int size;
    unsigned char *data;
} kept_frame;

static kept_frame kept[MAX_KEPT];
static int nkept, nsent_altered, nsent_forged, nsent_replayed;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static void on_frame(const lcm_recv_buf_t *rbuf, const char *channel, void *user)
{
    (void)user;
    /* small frames only (headers of STEP, STATUS, HELLO, heartbeats...): 45 bytes of header + MAC */
    if (nkept >= MAX_KEPT || rbuf->data_size < 80 || rbuf->data_size > 4096)
        return;
    kept_frame *k = &kept[nkept];
    k->data = malloc(rbuf->data_size);
    if (!k->data)
        return;
    memcpy(k->data, rbuf->data, rbuf->data_size);
    k->size = (int)rbuf->data_size;
    snprintf(k->channel, sizeof k->channel, "%s", channel);
    k->t = now();
    nkept++;
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: lahar_attack URL SECONDS\n");
        return 2;
    }
    lcm_t *lcm = lcm_create(argv[1]);
    if (!lcm) {
        fprintf(stderr, "lahar_attack: cannot open %s\n", argv[1]);
        return 2;
    }
    lcm_subscribe(lcm, "LAHAR_.*", on_frame, NULL);
    double end = now() + atof(argv[2]);
    int next = 0;
    while (now() < end) {
        lcm_handle_timeout(lcm, 20);
        while (next < nkept && now() - kept[next].t > 0.05) {
            kept_frame *k = &kept[next++];
            unsigned char *copy = malloc((size_t)k->size);
            if (!copy)
                continue;
            memcpy(copy, k->data, (size_t)k->size);
            copy[8 + 7] ^= 0x01; /* the run id's lowest byte (after the 8-byte type hash) */
            lcm_publish(lcm, k->channel, copy, (unsigned)k->size);
            nsent_altered++;
            memcpy(copy, k->data, (size_t)k->size);
            memset(copy + k->size - 32, 0, 32); /* the MAC */
            lcm_publish(lcm, k->channel, copy, (unsigned)k->size);
            nsent_forged++;
            lcm_publish(lcm, k->channel, k->data, (unsigned)k->size);
            nsent_replayed++;
            free(copy);
        }
    }
    printf("lahar_attack: heard %d frames; sent %d altered, %d forged, %d replayed\n", nkept, nsent_altered,
           nsent_forged, nsent_replayed);
    for (int i = 0; i < nkept; i++)
        free(kept[i].data);
    lcm_destroy(lcm);
    return 0;
}
