/*
 * bc_bind.h - what the host binding (Python, ctypes) needs to drive the core without restating it:
 * the layout of every struct it fills or reads (offsets from the compiler, so they cannot drift), the trace
 * fields (from BC_TRACE_FIELDS), the named constants (enum values and flag bits, by group), and the registry of
 * controllers with their init/step functions.
 * Host-side only: firmware does not link this file.
 */
#ifndef BC_BIND_H
#define BC_BIND_H

#include <stddef.h>
#include <stdint.h>

#include "bldc/bc_types.h"

typedef struct {
    const char *strct;  /* struct name, e.g. "bc_plant_params" */
    const char *field;  /* member name */
    const char *type;   /* "f8", "f4", "i4", "u4", "i8", "u8", "ptr", or the name of a struct in this table */
    uint32_t offset;    /* offsetof */
    uint32_t size;      /* sizeof the member (arrays: whole array) */
} bc_field_desc;

typedef struct {
    const char *name;
    uint32_t size;
} bc_struct_desc;

typedef struct {
    const char *name;                                /* e.g. "sixv" */
    const char *params;                              /* struct name of its params */
    const char *state;                               /* struct name of its state */
    int (*init)(const void *params, void *state);    /* validate params, reset state */
    bc_ctrl_step_fn step;
    const char *diag[BC_DIAG_N];                     /* meaning of diag[0..7] ("" unused) */
} bc_ctrl_info;

/* A named integer constant of the C API (an enum value or a flag bit), in a group of related ones: the host builds
 * its constants and flag decoders from these instead of restating the numbers. */
typedef struct {
    const char *group; /* e.g. "flag", "leg", "sixstep_reg" */
    const char *name;  /* the C macro's name, e.g. "BC_FLAG_SAFE" */
    int64_t value;
} bc_const_desc;

#define BC_BIND_CONST(group, NAME) {group, #NAME, (int64_t)(NAME)}

/* What one controller contributes to the binding: its structs' layouts and sizes, its constants and its registry
 * entry.
 * Each controller has a provider in host/src/bc_bind_<name>.c; bc_bind.c lists the providers once. */
typedef struct {
    const bc_field_desc *fields;
    int32_t n_fields;
    const bc_struct_desc *structs;
    int32_t n_structs;
    const bc_ctrl_info *info;
    const bc_const_desc *consts;
    int32_t n_consts;
} bc_bind_provider;

#define BC_BIND_FIELD(S, member, type) \
    {#S, #member, type, (uint32_t)offsetof(S, member), (uint32_t)sizeof(((S *)0)->member)}
#define BC_BIND_STRUCT(T) {#T, (uint32_t)sizeof(T)}

int32_t bc_layout_count(void);
const bc_field_desc *bc_layout_get(int32_t j);
int32_t bc_struct_count(void);
const bc_struct_desc *bc_struct_get(int32_t j);

int32_t bc_const_count(void);
const bc_const_desc *bc_const_get(int32_t j);

int32_t bc_trace_count(void);
const char *bc_trace_name(int32_t j);
const char *bc_trace_unit(int32_t j);
const char *bc_trace_doc(int32_t j);

int32_t bc_acc_count(void);
const char *bc_acc_name(int32_t j); /* names of bc_plant.h's integrated quantities acc[] */

int32_t bc_ctrl_count(void);
const bc_ctrl_info *bc_ctrl_get(int32_t j);

const char *bc_version(void);

#endif /* BC_BIND_H */
