/* placeholder */ typedef int lahar_placeholder_sph;
