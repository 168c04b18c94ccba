/* bc_commutation.c - Hall code, sector, conducting phases, a pair's leg commands. Table in bc_commutation.h. */
#include "bldc/bc_commutation.h"

#include "bldc/bc_math.h"
#include "bldc/bc_types.h"

int bc_hall_sector(uint32_t code)
{
    switch (code) {
    case 1u: return 0;
    case 3u: return 1;
    case 2u: return 2;
    case 6u: return 3;
    case 4u: return 4;
    case 5u: return 5;
    default: return -1;
    }
}

uint32_t bc_sector_code(int sector)
{
    static const uint32_t code[6] = {1u, 3u, 2u, 6u, 4u, 5u};
    return (sector >= 0 && sector < 6) ? code[sector] : 0u;
}

int bc_sector_phases(int sector, int *pos, int *neg)
{
    static const int p[6] = {0, 0, 1, 1, 2, 2};
    static const int n[6] = {1, 2, 2, 0, 0, 1};
    if (sector < 0 || sector > 5) return -1;
    *pos = p[sector];
    *neg = n[sector];
    return 0;
}

float bc_sector_angle(int sector)
{
    if (sector < 0 || sector > 5) return 0.0f;
    return BC_PI_F / 6.0f + (float)sector * (BC_PI_F / 3.0f);
}

void bc_pair_legs(int chop, int pos, int neg, int chop_leg, float m, bc_leg_cmd c[3])
{
    for (int x = 0; x < 3; ++x) {
        c[x].mode = BC_LEG_OFF;
        c[x].duty = 0.0f;
    }
    c[pos].mode = BC_LEG_HIGH;
    c[neg].mode = BC_LEG_LOW;
    if (chop == BC_CHOP_BIPOLAR || m < 0.0f) { /* u = (2 d - 1) V,  d = (1 + m)/2 */
        float d = bc_clampf(0.5f * (1.0f + m), 0.0f, 1.0f);
        c[pos].duty = d;
        c[neg].duty = d;
        return;
    }
    m = bc_clampf(m, 0.0f, 1.0f);
    switch (chop) {
    case BC_CHOP_PWMPWM: /* u = m V: one leg chops, the other is fully on */
        c[pos].duty = chop_leg == pos ? m : 1.0f;
        c[neg].duty = chop_leg == neg ? m : 1.0f;
        break;
    case BC_CHOP_SYNC:   /* u = m V */
        c[pos].mode = BC_LEG_PWM;
        c[pos].duty = m;
        c[neg].duty = 1.0f;
        break;
    default:             /* high side: u = m V */
        c[pos].duty = m;
        c[neg].duty = 1.0f;
        break;
    }
}
