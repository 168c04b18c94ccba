/* nosymbol.c - a library without the description (no BC_USER_CONTROLLER): refused when loaded. */
#include "bldc/bc_types.h"

void my_step(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out);

void my_step(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    (void)p;
    (void)s;
    (void)in;
    bc_legs_off(out);
}
