/* Message authentication for runs across machines: a shared secret key (32 bytes, written as 64
 * hex digits in a file only its owner reads) with which every frame carries a MAC (libsodium's
 * crypto_auth, HMAC-SHA-512-256) over its header (run id, sender, step, type, sequence number,
 * framing) and payload (common/protocol/link.c). The runs lahar keeps in its own network namespace need
 * none. */
#ifndef LAHAR_AUTH_H
#define LAHAR_AUTH_H
#include <stddef.h>
#include <stdint.h>

#define LAHAR_AUTH_KEYBYTES 32
#define LAHAR_AUTH_MACBYTES 32
#define LAHAR_AUTH_ENV "LAHAR_AUTH_KEY" /* the key file's path, when no --auth-key is given */

/* Read the key file `path` (64 hex digits, white space around them allowed). 0, or -1 with a
 * message naming the file and what is wrong in err. */
int lahar_auth_key_load(const char *path, uint8_t key[LAHAR_AUTH_KEYBYTES], char *err, size_t n);
/* Write a new random key to `path` (created, mode 0600; an existing file is not overwritten).
 * 0, or -1 with a message. */
int lahar_auth_keygen(const char *path, char *err, size_t n);

/* mac = MAC of data[0 .. size) under key; verify: 1 when mac is that of data. */
void lahar_auth_mac(uint8_t mac[LAHAR_AUTH_MACBYTES], const void *data, size_t size,
                    const uint8_t key[LAHAR_AUTH_KEYBYTES]);
int lahar_auth_verify(const uint8_t mac[LAHAR_AUTH_MACBYTES], const void *data, size_t size,
                      const uint8_t key[LAHAR_AUTH_KEYBYTES]);
#endif
