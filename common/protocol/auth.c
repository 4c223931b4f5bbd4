/* Keys and MACs of authenticated runs (auth.h), on libsodium. */
#include "auth.h"
#include "errmsg.h"
#include <errno.h>
#include <fcntl.h>
#include <sodium.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

_Static_assert(LAHAR_AUTH_KEYBYTES == crypto_auth_KEYBYTES, "crypto_auth key size");
_Static_assert(LAHAR_AUTH_MACBYTES == crypto_auth_BYTES, "crypto_auth MAC size");

static int auth_init(char *err, size_t n)
{
    if (sodium_init() < 0) {
        snprintf(err, n, "libsodium cannot be initialised");
        return -1;
    }
    return 0;
}

int lahar_auth_key_load(const char *path, uint8_t key[LAHAR_AUTH_KEYBYTES], char *err, size_t n)
{
    if (auth_init(err, n) != 0)
        return -1;
    FILE *f = lahar_fopen_input(path, "r");
    if (!f) {
        snprintf(err, n, "auth key %s: %s (make one with `lahar keygen %s`)", path, strerror(errno), path);
        return -1;
    }
    char text[256];
    size_t len = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[len] = '\0';
    size_t bin_len = 0;
    const char *end = NULL;
    const char *s = text;
    while (*s == ' ' || *s == '\t' || *s == '\n' || *s == '\r')
        s++;
    if (sodium_hex2bin(key, LAHAR_AUTH_KEYBYTES, s, strlen(s), NULL, &bin_len, &end) != 0 ||
        bin_len != LAHAR_AUTH_KEYBYTES || strspn(end, " \t\r\n") != strlen(end)) {
        snprintf(err, n, "auth key %s: expected %d hex digits (a key made by `lahar keygen FILE`)", path,
                 2 * LAHAR_AUTH_KEYBYTES);
        sodium_memzero(key, LAHAR_AUTH_KEYBYTES);
        return -1;
    }
    sodium_memzero(text, sizeof text);
    return 0;
}

int lahar_auth_keygen(const char *path, char *err, size_t n)
{
    if (auth_init(err, n) != 0)
        return -1;
    int fd = open(path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd < 0) {
        snprintf(err, n, "%s: %s%s", path, strerror(errno),
                 errno == EEXIST ? " (an existing key is never overwritten; remove it first)" : "");
        return -1;
    }
    uint8_t key[LAHAR_AUTH_KEYBYTES];
    char hex[2 * LAHAR_AUTH_KEYBYTES + 2];
    crypto_auth_keygen(key);
    sodium_bin2hex(hex, sizeof hex - 1, key, sizeof key);
    size_t len = strlen(hex);
    hex[len++] = '\n';
    int rc = write(fd, hex, len) == (ssize_t)len && fsync(fd) == 0 ? 0 : -1;
    if (rc != 0)
        snprintf(err, n, "%s: %s", path, strerror(errno));
    close(fd);
    sodium_memzero(key, sizeof key);
    sodium_memzero(hex, sizeof hex);
    return rc;
}

void lahar_auth_mac(uint8_t mac[LAHAR_AUTH_MACBYTES], const void *data, size_t size,
                    const uint8_t key[LAHAR_AUTH_KEYBYTES])
{
    crypto_auth(mac, data, size, key);
}

int lahar_auth_verify(const uint8_t mac[LAHAR_AUTH_MACBYTES], const void *data, size_t size,
                      const uint8_t key[LAHAR_AUTH_KEYBYTES])
{
    return crypto_auth_verify(mac, data, size, key) == 0;
}
