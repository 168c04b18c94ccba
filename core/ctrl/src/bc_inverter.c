/* bc_inverter.c - the shared average model of inverter and motor over a piece. Equations in bc_inverter.h. */
#include "bldc/bc_inverter.h"

int bc_inv_slopes(const float u[3], const float a[3], const float b[3], const int conn[3], float L, float slope[3])
{
    int n = 0;
    float sum = 0.0f;
    for (int x = 0; x < 3; ++x) {
        slope[x] = 0.0f;
        if (conn[x]) {
            ++n;
            sum += u[x] - a[x] - b[x];
        }
    }
    if (n < 2) return BC_INV_NO_PATH;
    float vn = sum / (float)n;
    for (int x = 0; x < 3; ++x) slope[x] = conn[x] ? (u[x] - a[x] - b[x] - vn) / L : 0.0f;
    return n;
}

int bc_inv_first_zero(const int diode[3], const float i[3], const float slope[3], float h_max, float *h)
{
    int z = -1;
    *h = h_max;
    for (int x = 0; x < 3; ++x) {
        if (diode[x] && i[x] * slope[x] < 0.0f) {
            float t = -i[x] / slope[x];
            if (t < *h) {
                *h = t;
                z = x;
            }
        }
    }
    return z;
}

void bc_inv_advance(const int conn[3], const float slope[3], float h, int z, float i[3])
{
    for (int x = 0; x < 3; ++x) i[x] += slope[x] * h;
    if (z < 0) return;
    float r = i[z]; /* rounding residue: keep the sum zero */
    i[z] = 0.0f;
    for (int x = 0; x < 3; ++x) {
        if (x != z && conn[x]) {
            i[x] += r;
            return;
        }
    }
}
