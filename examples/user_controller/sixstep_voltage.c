/* sixstep_voltage.c - the C translation of prototype.py (a Python prototype): the same law, the same trace.
 *
 * The Hall code gives the sector, the sector the conducting pair; the positive phase's upper switch chops with the
 * duty gain * ref (limited to [0, 1]), the negative phase's lower switch is on, the third leg is off. */
#include <stdint.h>

#include "bldc/bc_commutation.h"
#include "bldc/bc_types.h"
#include "bldc/bc_user.h"

typedef struct {
    float gain; /* duty per unit reference */
} sv_params;

typedef struct {
    int32_t unused; /* no state */
} sv_state;

static int sv_init(const sv_params *p, sv_state *s)
{
    s->unused = 0;
    return (p->gain >= 0.0f && p->gain <= 1e6f) ? BC_OK : BC_ERR_PARAM;
}

static void sv_step(const sv_params *p, sv_state *s, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    (void)s;
    int sector = bc_hall_sector(in->hall);
    out->diag[0] = (float)sector;
    if (sector < 0) { /* 000 or 111: a broken sensor; all legs off */
        bc_legs_off(out);
        out->flags |= BC_FLAG_HALL_INVALID;
        return;
    }
    /* the other legs: off, as the output arrives cleared (all zero: BC_LEG_OFF, duty 0) */
    float d = p->gain * in->ref;
    d = d > 0.0f ? d : 0.0f; /* max(d, 0), min(d, 1) as Python's max/min: NaN -> 0 */
    d = d < 1.0f ? d : 1.0f;
    int pos, neg;
    (void)bc_sector_phases(sector, &pos, &neg);
    out->leg[pos].mode = BC_LEG_HIGH;
    out->leg[pos].duty = d;
    out->leg[neg].mode = BC_LEG_LOW;
    out->leg[neg].duty = 1.0f;
}

static const bc_field_desc SV_FIELDS[] = {BC_BIND_FIELD(sv_params, gain, "f4")};

static const bc_user_desc SV = {
    .name = "sixstep_voltage",
    .fields = SV_FIELDS,
    .n_fields = BC_USER_COUNT(SV_FIELDS),
    .diag = {"sector"},
    .ref = "duty per unit gain",
};

BC_USER_CONTROLLER(SV, sv_params, sv_state, sv_init, sv_step);
