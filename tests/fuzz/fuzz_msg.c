/* Harness: the typed decoders. First byte: the message type (frame_t.MSG_*, taken mod 10); the
 * rest: the LCM encoding as it arrives, reassembled, from the link. */
#include "fuzz.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1 || size > (1u << 22))
        return 0;
    fuzz_decode_message(data[0] % 10, data + 1, (int)(size - 1));
    return 0;
}
