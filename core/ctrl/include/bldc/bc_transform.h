/*
 * bc_transform.h - three-phase quantities as small named structs, the amplitude-invariant Clarke and Park
 * transforms, and min-max (space-vector) modulation (float).
 *
 * Axes (docs/sine.md): alpha along phase a; d along the rotor PM flux; q 90 degrees ahead of d. bldclab's angle
 * theta_e is 0 where phase a's back-EMF fundamental crosses zero rising (docs/conventions.md), so the back-EMF
 * vector points along q when the d axis sits at theta_d = theta_e - pi (bc_theta_d). Paper 1 calls its torque axis
 * "d" ((45)): its d is our q.
 *
 * Clarke (amplitude invariant: a balanced set of peak I gives a vector of length I; the zero sequence is dropped)
 *
 *     alpha = (2 a - b - c) / 3,   beta = (b - c) / sqrt(3)
 *
 * inverse Clarke (no zero sequence)
 *
 *     a = alpha,   b = -alpha/2 + sqrt(3)/2 beta,   c = -alpha/2 - sqrt(3)/2 beta
 *
 * Park at the d-axis angle theta_d, given s = sin(theta_d), c = cos(theta_d), and its inverse
 *
 *     d =  alpha c + beta s,      alpha = d c - q s
 *     q = -alpha s + beta c,      beta  = d s + q c
 *
 * Check: i_x = I sin(theta_e - x 2 pi/3) gives alpha = I sin(theta_e), beta = -I cos(theta_e), and with
 * theta_d = theta_e - pi: d = 0, q = I.
 *
 * Min-max modulation (centre-aligned, complementary legs): with v_mid = (max_x v_x + min_x v_x) / 2,
 *
 *     d_x = 1/2 + (v_x - v_mid) / V_dc                                   (bc_svm)
 *
 * The zero-sequence shift -v_mid centres the three references between the rails; the line voltages averaged over
 * a half period equal the references' differences as long as max - min <= V_dc (linear modulation: the hexagon;
 * for a balanced sinusoidal set that is a peak of V_dc / sqrt(3), the hexagon's inscribed circle). Beyond it the
 * duties are clipped to [0, 1] and BC_SVM_CLIPPED is returned.
 */
#ifndef BC_TRANSFORM_H
#define BC_TRANSFORM_H

typedef struct {
    float a, b, c;
} bc_abc;

typedef struct {
    float alpha, beta;
} bc_ab;

typedef struct {
    float d, q;
} bc_dq;

#define BC_SQRT3_F 1.73205081f
#define BC_INV_SQRT3_F 0.577350269f

/* Amplitude-invariant Clarke transform (zero sequence dropped). */
bc_ab bc_clarke(bc_abc x);

/* Inverse Clarke transform (no zero sequence). */
bc_abc bc_clarke_inv(bc_ab x);

/* Park transform at the d-axis angle, given s = sin(theta_d), c = cos(theta_d). */
bc_dq bc_park(bc_ab x, float s, float c);

/* Inverse Park transform, given s = sin(theta_d), c = cos(theta_d). */
bc_ab bc_park_inv(bc_dq x, float s, float c);

/* d-axis angle of bldclab's electrical angle: theta_d = theta_e - pi, wrapped to [0, 2 pi). */
float bc_theta_d(float theta_e);

/* Angle wrapped to [0, 2 pi); non-finite gives 0. */
float bc_wrap_2pi(float theta);

#define BC_SVM_LINEAR 0
#define BC_SVM_CLIPPED 1

/* Min-max modulation of phase voltage references on the bus v_dc (> 0): duties in [0, 1]. Returns BC_SVM_LINEAR
 * or BC_SVM_CLIPPED. Non-finite references or v_dc give duties of 1/2 and BC_SVM_CLIPPED. */
int bc_svm(bc_abc v, float v_dc, float duty[3]);

#endif /* BC_TRANSFORM_H */
