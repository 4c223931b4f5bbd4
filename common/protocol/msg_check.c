/* Walk an LCM encoding with lcm-gen's type information before decoding it (msg_check.h). */
#include "msg_check.h"
#include <stdlib.h>
#include <string.h>
#include "lahar_lcm_types.h" /* every type of lcm_types/, written by CMake */

#define MSG_MAX_DEPTH 8 /* nesting of the lahar types is 2 deep; a deeper walk is a bug */

/* The type named by a field's typestr ("material_t" or "lahar.material_t"), or NULL. */
static const lcm_type_info_t *msg_type(const char *typestr)
{
    static const struct {
        const char *name;
        const lcm_type_info_t *(*info)(void);
    } types[] = {
#define LAHAR_LCM_TYPE(stem) {#stem, lahar_##stem##_get_type_info},
        LAHAR_LCM_TYPES
#undef LAHAR_LCM_TYPE
    };
    const char *dot = strrchr(typestr, '.');
    const char *name = dot ? dot + 1 : typestr;
    for (size_t i = 0; i < sizeof types / sizeof types[0]; i++)
        if (strcmp(types[i].name, name) == 0)
            return types[i].info();
    return NULL;
}

static int msg_prim_size(lcm_field_type_t t)
{
    switch (t) {
    case LCM_FIELD_INT8_T: case LCM_FIELD_BYTE: case LCM_FIELD_BOOLEAN: return 1;
    case LCM_FIELD_INT16_T: return 2;
    case LCM_FIELD_INT32_T: case LCM_FIELD_FLOAT: return 4;
    case LCM_FIELD_INT64_T: case LCM_FIELD_DOUBLE: return 8;
    default: return 0;
    }
}

/* A scalar primitive decoded into its place in the scratch struct (counts are read from there). */
static int msg_scalar(lcm_field_type_t t, const void *buf, int pos, int size, void *dst)
{
    switch (t) {
    case LCM_FIELD_INT8_T: case LCM_FIELD_BOOLEAN: return __int8_t_decode_array(buf, pos, size - pos, dst, 1);
    case LCM_FIELD_BYTE: return __byte_decode_array(buf, pos, size - pos, dst, 1);
    case LCM_FIELD_INT16_T: return __int16_t_decode_array(buf, pos, size - pos, dst, 1);
    case LCM_FIELD_INT32_T: return __int32_t_decode_array(buf, pos, size - pos, dst, 1);
    case LCM_FIELD_INT64_T: return __int64_t_decode_array(buf, pos, size - pos, dst, 1);
    case LCM_FIELD_FLOAT: return __float_decode_array(buf, pos, size - pos, dst, 1);
    case LCM_FIELD_DOUBLE: return __double_decode_array(buf, pos, size - pos, dst, 1);
    default: return -1;
    }
}

/* A string: int32 length counting the NUL, >= 1, within the bytes, ending with the NUL. */
static int msg_string(const void *buf, int *pos, int size)
{
    int32_t len;
    int n = __int32_t_decode_array(buf, *pos, size - *pos, &len, 1);
    if (n < 0)
        return -1;
    *pos += n;
    if (len < 1 || len > size - *pos || ((const char *)buf)[*pos + len - 1] != '\0')
        return -1;
    *pos += len;
    return 0;
}

static int msg_walk(const lcm_type_info_t *ti, const void *buf, int *pos, int size, int depth)
{
    if (!ti || depth > MSG_MAX_DEPTH)
        return -1;
    void *scratch = calloc(1, (size_t)ti->struct_size());
    if (!scratch)
        return -1;
    int rc = 0, nf = ti->num_fields();
    for (int i = 0; i < nf && rc == 0; i++) {
        lcm_field_t f;
        memset(&f, 0, sizeof f);
        if (ti->get_field(scratch, i, &f) != 0) {
            rc = -1;
            break;
        }
        int esz = msg_prim_size(f.type);
        if (f.num_dim == 0 && esz > 0) {
            int n = msg_scalar(f.type, buf, *pos, size, f.data);
            if (n < 0)
                rc = -1;
            else
                *pos += n;
            continue;
        }
        /* elements of the field: the product of its dimensions, the variable ones read above;
         * every element takes at least one byte, so more than the bytes left is malformed */
        int64_t count = 1;
        for (int d = 0; d < f.num_dim && rc == 0; d++) {
            if (f.dim_size[d] < 0)
                rc = -1;
            else if ((count *= f.dim_size[d]) > size - *pos)
                rc = -1;
        }
        if (rc)
            break;
        if (esz > 0) {
            if (count > (size - *pos) / esz)
                rc = -1;
            else
                *pos += (int)count * esz;
        } else if (f.type == LCM_FIELD_STRING) {
            for (int64_t k = 0; k < count && rc == 0; k++)
                rc = msg_string(buf, pos, size);
        } else if (f.type == LCM_FIELD_USER_TYPE) {
            const lcm_type_info_t *sub = msg_type(f.typestr);
            for (int64_t k = 0; k < count && rc == 0; k++)
                rc = msg_walk(sub, buf, pos, size, depth + 1);
        } else {
            rc = -1;
        }
    }
    free(scratch);
    return rc;
}

int lahar_msg_check(const lcm_type_info_t *ti, const void *data, int size)
{
    if (!ti || !data || size < 8)
        return -1;
    int64_t hash;
    if (__int64_t_decode_array(data, 0, size, &hash, 1) != 8 || hash != ti->get_hash())
        return -1;
    int pos = 8;
    return msg_walk(ti, data, &pos, size, 0);
}
