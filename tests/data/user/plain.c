/* plain.c - sixstep_voltage.c's law with the parameters of plain.h (no description here: --params-header). */
#include "plain.h"

#include "bldc/bc_commutation.h"

int plain_init(const plain_params *p, plain_state *s)
{
    s->k = 0;
    return (p->limits.lo <= p->limits.hi) ? BC_OK : BC_ERR_PARAM;
}

void plain_step(const plain_params *p, plain_state *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    s->k += 1;
    int sector = bc_hall_sector(in->hall);
    out->diag[0] = (float)sector;
    if (sector < 0) {
        bc_legs_off(out);
        out->flags |= BC_FLAG_HALL_INVALID;
        return;
    }
    float d = p->gain * in->ref;
    d = d > p->limits.lo ? d : p->limits.lo;
    d = d < p->limits.hi ? d : p->limits.hi;
    int pos, neg;
    (void)bc_sector_phases(sector, &pos, &neg);
    out->leg[p->order[pos]].mode = BC_LEG_HIGH;
    out->leg[p->order[pos]].duty = d;
    out->leg[p->order[neg]].mode = BC_LEG_LOW;
    out->leg[p->order[neg]].duty = 1.0f;
}
