/* bc_openloop.c - table replay and six-step voltage mode. Laws in bc_openloop.h. */
#include "bldc/bc_openloop.h"

#include <math.h>

#include "bldc/bc_commutation.h"

static void clear_out(bc_ctrl_out *out)
{
    for (int j = 0; j < BC_DIAG_N; ++j) out->diag[j] = 0.0f;
    out->flags = 0u;
}

int bc_table_init(const bc_table_params *p, bc_table_state *s)
{
    if (p == 0 || s == 0 || p->n < 0 || (p->n > 0 && p->cmd == 0)) return BC_ERR_PARAM;
    s->k = 0;
    return BC_OK;
}

void bc_table_step(const bc_table_params *p, bc_table_state *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    (void)in;
    clear_out(out);
    if (s->k < 0 || s->k >= p->n) {
        bc_legs_off(out);
        return;
    }
    for (int x = 0; x < 3; ++x) {
        bc_leg_cmd c = p->cmd[3 * s->k + x];
        if (c.mode < BC_LEG_OFF || c.mode > BC_LEG_LOW || !(c.duty >= 0.0f && c.duty <= 1.0f)) {
            c.mode = BC_LEG_OFF; /* never pass a bad command on */
            c.duty = 0.0f;
            out->flags |= BC_FLAG_BAD_INPUT;
        }
        out->leg[x] = c;
    }
    s->k += 1;
}

int bc_sixv_init(const bc_sixv_params *p, bc_sixv_state *s)
{
    if (p == 0 || s == 0 || p->chop < BC_SIXV_HIGH || p->chop > BC_SIXV_SYNC) return BC_ERR_PARAM;
    s->sector = -1;
    return BC_OK;
}

void bc_sixv_step(const bc_sixv_params *p, bc_sixv_state *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    clear_out(out);
    int sector = bc_hall_sector(in->hall);
    out->diag[0] = (float)sector;
    float u = in->ref;
    if (sector < 0 || !isfinite(u)) {
        out->flags |= (sector < 0 ? BC_FLAG_HALL_INVALID : BC_FLAG_BAD_INPUT);
        bc_legs_off(out);
        return;
    }
    s->sector = sector;
    int pos, neg;
    (void)bc_sector_phases(sector, &pos, &neg);
    if (u < 0.0f) {
        int t = pos;
        pos = neg;
        neg = t;
        u = -u;
    }
    if (u > 1.0f) {
        u = 1.0f;
        out->flags |= BC_FLAG_SATURATED;
    }
    out->diag[1] = u;
    for (int x = 0; x < 3; ++x) {
        out->leg[x].mode = BC_LEG_OFF;
        out->leg[x].duty = 0.0f;
    }
    switch (p->chop) {
    case BC_SIXV_LOW:
        out->leg[pos].mode = BC_LEG_HIGH;
        out->leg[pos].duty = 1.0f;
        out->leg[neg].mode = BC_LEG_LOW;
        out->leg[neg].duty = u;
        break;
    case BC_SIXV_BIPOLAR:
        out->leg[pos].mode = BC_LEG_HIGH;
        out->leg[pos].duty = u;
        out->leg[neg].mode = BC_LEG_LOW;
        out->leg[neg].duty = u;
        break;
    case BC_SIXV_SYNC:
        out->leg[pos].mode = BC_LEG_PWM;
        out->leg[pos].duty = u;
        out->leg[neg].mode = BC_LEG_LOW;
        out->leg[neg].duty = 1.0f;
        break;
    default:
        out->leg[pos].mode = BC_LEG_HIGH;
        out->leg[pos].duty = u;
        out->leg[neg].mode = BC_LEG_LOW;
        out->leg[neg].duty = 1.0f;
        break;
    }
}
