/* placeholder */ typedef int lahar_placeholder_common;
