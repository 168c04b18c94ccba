/* bc_commutation.c - Hall code, sector, conducting phases. Table in bc_commutation.h. */
#include "bldc/bc_commutation.h"

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
