/* Checking an LCM encoding before the generated decoder sees it.
 *
 * The decoders lcm-gen writes (liblcm 1.3.1) trust the bytes: a negative string or array length
 * reaches memcpy as a huge size, a string without its terminating NUL is handed out as one, a
 * huge count allocates before the bytes run out, and a decode that fails half way leaks what it
 * allocated. Everything a process decodes from the network with a generated decoder therefore
 * goes through lahar_msg_check first: it walks the encoding field by field with the type
 * information lcm-gen itself emits (--c-typeinfo), without allocating per element, and accepts
 * it only when every length is >= 0 and within the bytes and every string ends with its NUL
 * inside them. The generated decoder of an accepted encoding reads only bytes that are there and
 * cannot fail except for lack of memory, which stays in proportion to the message's size. */
#ifndef LAHAR_MSG_CHECK_H
#define LAHAR_MSG_CHECK_H
#include <lcm/lcm_coretypes.h>

/* 0 when data[0 .. size) starts with a complete, well-formed encoding of type ti (fingerprint
 * included), -1 otherwise. Nested types are found among the types of lcm_types/. */
int lahar_msg_check(const lcm_type_info_t *ti, const void *data, int size);

/* Decode a message of generated type T (e.g. lahar_scene_t) from data[0 .. size) into *p after
 * lahar_msg_check; evaluates to the generated decoder's result (bytes used), or -1 with *p left
 * untouched (nothing to clean up). */
#define LAHAR_MSG_DECODE(T, data, size, p)                                                        \
    (lahar_msg_check(T##_get_type_info(), (data), (size)) == 0 ? T##_decode((data), 0, (size), (p)) : -1)

#endif
