/* Copying a field between the in-memory case and its scene message under the same name, with
 * `from` and `to` in scope: NUM fields have the same type on both sides, FLAG fields are booleans
 * sent as int8, CODE fields small integers (enums, counts) sent as int8, ARRAY fields fixed-size
 * arrays. Each message lists its fields once (X-macros) and applies these both ways
 * (scene_msg.c, scene_msg_inflow.c). Private to common/protocol/. */
#ifndef LAHAR_SCENE_MSG_FIELDS_H
#define LAHAR_SCENE_MSG_FIELDS_H
#include <stdint.h>
#include <string.h>

#define TO_MSG_NUM(f) to->f = from->f;
#define TO_MSG_FLAG(f) to->f = (int8_t)(from->f != 0);
#define TO_MSG_CODE(f) to->f = (int8_t)from->f;
#define FROM_MSG_FLAG(f) to->f = from->f != 0;
#define FROM_MSG_CODE(f) to->f = from->f;
#define COPY_ARRAY(f) memcpy(to->f, from->f, sizeof to->f);

#endif
