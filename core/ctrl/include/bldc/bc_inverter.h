/*
 * bc_inverter.h - the average model of the inverter and the Y-connected motor over a short piece of time, shared
 * by the controllers that predict their currents (bc_sixstep's predictive law, bc_lu's ordered half-period model).
 *
 * Each caller decides what every terminal does over the piece (its own leg model): u_x, the terminal voltage, and
 * whether phase x is connected (a switch on, or a diode conducting) and diode-only (it conducts only through a diode
 * and opens when its current reaches zero). With the voltage terms a_x, b_x (back-EMF and resistive drop, frozen
 * over the piece: each caller says which is which, and the order keeps its rounding), over the connected set C:
 *
 *     v_n        = mean_C ((u_x - a_x) - b_x)                           star point (sum of the currents = 0)
 *     L di_x/dt  = (u_x - a_x) - b_x - v_n     (x in C),    0  (x open)
 *
 * Fewer than two connected phases close no path: no current (bc_inv_slopes returns BC_INV_NO_PATH).
 *
 * The piece ends at h_max or where the first diode-only phase with i_x di_x/dt < 0 reaches zero,
 * t_x = -i_x / (di_x/dt) (bc_inv_first_zero); bc_inv_advance moves the currents to the end of the piece and, if a
 * phase opened there, sets it to exactly 0 and gives its rounding residue to the first other connected phase (the
 * sum of the currents stays zero). Callers loop: classify, slopes, first zero, advance, until the time is used.
 *
 * Header-only (static inline): the callers run it several times per sample inside their solvers, and a call across
 * translation units cost them about 12 % more instructions per step (benchmarks/firmware.py).
 */
#ifndef BC_INVERTER_H
#define BC_INVERTER_H

#define BC_INV_NO_PATH (-2)

/* Slopes di_x/dt of the connected phases (0 for open ones); returns the number of connected phases, or
 * BC_INV_NO_PATH (slopes all 0) if fewer than two. */
static inline int bc_inv_slopes(const float u[3], const float a[3], const float b[3], const int conn[3], float L,
                                float slope[3])
{
    int n = 0;
    float sum = 0.0f, w[3]; /* w = (u - a) - b, once per phase */
    for (int x = 0; x < 3; ++x) {
        w[x] = u[x] - a[x] - b[x];
        if (conn[x]) {
            ++n;
            sum += w[x];
        }
    }
    if (n < 2) {
        slope[0] = slope[1] = slope[2] = 0.0f;
        return BC_INV_NO_PATH;
    }
    float vn = sum / (float)n;
    for (int x = 0; x < 3; ++x) slope[x] = conn[x] ? (w[x] - vn) / L : 0.0f;
    return n;
}

/* The first diode-only phase whose current reaches zero within h_max: returns its index and its time in *h, or -1
 * and *h = h_max. */
static inline int bc_inv_first_zero(const int diode[3], const float i[3], const float slope[3], float h_max,
                                    float *h)
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

/* i_x += slope_x h; if z >= 0 phase z opens: i_z = 0 and its residue goes to the first other connected phase. */
static inline void bc_inv_advance(const int conn[3], const float slope[3], float h, int z, float i[3])
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

#endif /* BC_INVERTER_H */
