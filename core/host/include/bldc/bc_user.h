/*
 * bc_user.h - a user's controller in the loop: how a controller built outside bldclab (a firmware's control step)
 * describes itself to the host (docs/user-controller.md).
 *
 * A user controller is the bc_types.h contract over the user's own structs:
 *
 *     int  my_init(const my_params *p, my_state *s);            validates p, resets s: BC_OK or an error code
 *     void my_step(const my_params *p, my_state *s, const bc_ctrl_in *in, bc_ctrl_out *out);    one sample
 *
 * and one description, in the tables the core describes its own structs with (bc_bind.h: names, types, and the
 * offsets and sizes the compiler gives), so that Python fills the parameters by name and nothing is restated:
 *
 *     static const bc_field_desc MY_FIELDS[] = {
 *         BC_BIND_FIELD(my_params, kp, "f4"),      every member of my_params ("f4" float, "f8" double, "i4"
 *         BC_BIND_FIELD(my_params, ki, "f4"),      int32_t, "u4" uint32_t, "i8", "u8", "i2", "u2", "i1", "u1", or
 *     };                                           the name of a described struct: nested members)
 *     static const bc_user_desc MY = {
 *         .name = "my",
 *         .fields = MY_FIELDS, .n_fields = BC_USER_COUNT(MY_FIELDS),
 *         .diag = {"sector", "i_reg A", "", "", "", "", "", ""},   diag[j]'s name and unit ("" unused)
 *     };
 *     BC_USER_CONTROLLER(MY, my_params, my_state, my_init, my_step);
 *
 * BC_USER_CONTROLLER type-checks init and step against the structs (through two adapters) and exports one symbol,
 * bc_user_controller, that records what the library was compiled against: the size of bc_ctrl_in and bc_ctrl_out,
 * BC_DIAG_N and BC_USER_ABI. `bldclab controller build` compiles the user's files with the core's warnings as
 * errors and links bldclab's controller blocks (core/ctrl: bc_hall, bc_pi, bc_guard, ...) as a static library; with
 * --params-header it writes this description itself from a header declaring X_params, X_state, X_init, X_step.
 * The host runs the step through a guard (bc_userguard.h) that checks every output against the contract.
 */
#ifndef BC_USER_H
#define BC_USER_H

#include <stdint.h>

#include "bldc/bc_bind.h"
#include "bldc/bc_types.h"

/* Version of this description and of bc_types.h's contract; a library built against another is refused. */
#define BC_USER_ABI 3 /* 2: bc_ctrl_in.temp, the temperature sensors (issue 27); 3: bc_ctrl_in.i_fs, the current
                         readings' full scale */

#define BC_USER_COUNT(table) ((int32_t)(sizeof(table) / sizeof((table)[0])))

/* What the user writes (see above). */
typedef struct {
    const char *name;              /* short name for messages and results */
    const bc_field_desc *fields;   /* every member of the params struct (and of the nested structs it names) */
    int32_t n_fields;
    const bc_struct_desc *structs; /* sizes of the nested structs the fields name (params and state: implicit) */
    int32_t n_structs;
    const char *diag[BC_DIAG_N];   /* meaning of diag[0..7]: "name" or "name unit" ("" or NULL: unused) */
    const bc_const_desc *consts;   /* named values a parameter may take (enum macros), by group */
    int32_t n_consts;
    const void *defaults;          /* NULL, or a params struct: the value of every member a user leaves unset */
    const char *ref;               /* what in->ref means, e.g. "current amplitude, A" (NULL: unstated) */
    int32_t bemf_sensing;          /* 1: reads the back-EMF sensing (in->zc_*, v_term, v_neutral): the host turns it on */
} bc_user_desc;

/* What BC_USER_CONTROLLER exports as bc_user_controller. */
typedef struct {
    uint32_t abi;          /* BC_USER_ABI */
    uint32_t size_in;      /* sizeof(bc_ctrl_in) as compiled */
    uint32_t size_out;     /* sizeof(bc_ctrl_out) */
    uint32_t diag_n;       /* BC_DIAG_N */
    const char *built_by;  /* BC_USER_BUILT_BY: the bldclab that built it ("" by hand) */
    const bc_user_desc *desc;
    const char *params;    /* struct names */
    const char *state;
    uint32_t params_size;  /* sizeof */
    uint32_t state_size;
    int (*init)(const void *params, void *state);
    bc_ctrl_step_fn step;
} bc_user_entry;

#ifndef BC_USER_BUILT_BY
#define BC_USER_BUILT_BY ""
#endif

#if defined(__GNUC__)
#define BC_USER_EXPORT __attribute__((visibility("default")))
#else
#define BC_USER_EXPORT
#endif

/* The adapters (typed init and step through void pointers, checked by the compiler) and the exported entry. */
#define BC_USER_CONTROLLER(DESC, P, S, INIT, STEP)                                                                  \
    static int bc_user_init_adapter(const void *p, void *s) { return INIT((const P *)p, (S *)s); }                  \
    static void bc_user_step_adapter(const void *p, void *s, const bc_ctrl_in *in, bc_ctrl_out *out)                \
    {                                                                                                               \
        STEP((const P *)p, (S *)s, in, out);                                                                        \
    }                                                                                                               \
    BC_USER_EXPORT extern const bc_user_entry bc_user_controller;                                                   \
    BC_USER_EXPORT const bc_user_entry bc_user_controller = {                                                       \
        BC_USER_ABI, (uint32_t)sizeof(bc_ctrl_in), (uint32_t)sizeof(bc_ctrl_out), BC_DIAG_N, BC_USER_BUILT_BY,      \
        &(DESC), #P, #S, (uint32_t)sizeof(P), (uint32_t)sizeof(S), bc_user_init_adapter, bc_user_step_adapter}

#endif /* BC_USER_H */
