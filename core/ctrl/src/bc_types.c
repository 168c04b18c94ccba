/* bc_types.c - helpers shared by every controller. */
#include "bldc/bc_types.h"

void bc_legs_off(bc_ctrl_out *out)
{
    for (int x = 0; x < 3; ++x) {
        out->leg[x].mode = BC_LEG_OFF;
        out->leg[x].duty = 0.0f;
        out->leg_at[x] = out->leg[x];
    }
    out->has_at = 0u; /* no timed change either */
    out->t_at = 0.0f;
    out->flags |= BC_FLAG_SAFE;
}
