/*
 * bc_userguard.h - the host's guard around a user's controller (bc_user.h): progress for a watching parent, the
 * output checked against the contract at every sample, and the end of the run at the first violation.
 *
 * The runner (bc_sim.h) calls bc_user_step through its controller slot with a bc_user_guard as its state;
 * bc_user_step calls the user's step and checks what it returned, sample by sample:
 *
 *   1. watch->k = k, watch->busy = 1 (a parent process watching a child reads these: which sample, and whether a
 *      call into user code has returned: the step-time budget);
 *   2. copy the measurements into the guard's own bc_ctrl_in (g->in: placed by the host against a page it cannot
 *      access, so a read past its end faults), clear the guard's bc_ctrl_out (g->out, likewise), call the step;
 *   3. watch->busy = 0; a Python controller that raised sets g->stop; a changed copy of the measurements is a write
 *      to const inputs; every leg mode must be OFF, PWM, HIGH or LOW (BC_LEG_HOLD is the plant's idealisation, not
 *      a command), every duty finite and in [0, 1], has_at 0 or 1 and t_at finite and >= 0 with it (then leg_at as
 *      leg), every diagnostic and i_hold finite;
 *   4. the first violation is written to the watch (fault, where, index, value) and ends the run: inside
 *      bc_user_run, by longjmp to its start (the runner's state is then unusable: the run is over); otherwise the
 *      legs are turned off. The output is copied to the runner's out.
 *
 * bc_user_arm installs handlers of the signals a crash raises (SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT) on their
 * own stack: the handler writes the signal and the faulting address to the watch and lets the process die of it.
 * It is meant for a child process that runs user code for a parent which survives it; POSIX only (elsewhere it
 * returns BC_ERR_PARAM).
 */
#ifndef BC_USERGUARD_H
#define BC_USERGUARD_H

#include <stdint.h>

#include "bldc/bc_sim.h"
#include "bldc/bc_types.h"

/* watch->fault */
#define BC_USER_FAULT_NONE 0
#define BC_USER_FAULT_OUTPUT 1  /* an output value out of the contract (where, index, value) */
#define BC_USER_FAULT_INPUT 2   /* wrote to its const inputs (index: first byte changed) */
#define BC_USER_FAULT_STOP 3    /* the controller asked to stop (a Python controller raised) */
#define BC_USER_FAULT_SIGNAL 4  /* the process received a crash signal (signo, addr) */

/* watch->where: the output field at fault */
#define BC_USER_AT_MODE 1     /* leg[index].mode */
#define BC_USER_AT_DUTY 2     /* leg[index].duty */
#define BC_USER_AT_HAS_AT 3   /* has_at */
#define BC_USER_AT_T_AT 4     /* t_at */
#define BC_USER_AT_MODE_AT 5  /* leg_at[index].mode */
#define BC_USER_AT_DUTY_AT 6  /* leg_at[index].duty */
#define BC_USER_AT_DIAG 7     /* diag[index] */
#define BC_USER_AT_HOLD 8     /* i_hold (index 0) or i_hold_at (index 1) */

/* bc_user_run's return value when the guard ended the run (the watch says why) */
#define BC_USER_STOPPED 1

/* Progress and faults of a guarded controller: shared memory between a child that runs it and its parent. */
typedef struct {
    volatile int64_t k;        /* sample of the call in progress (or the last one); -1: init */
    volatile uint64_t entered; /* calls into user code entered (init and steps) */
    volatile uint64_t done;    /* ... and returned */
    volatile int32_t busy;     /* 1 while a call into user code runs */
    int32_t fault;             /* BC_USER_FAULT_* */
    int32_t where;             /* BC_USER_AT_* */
    int32_t index;             /* leg or diagnostic index, or byte offset */
    double value;              /* the value at fault */
    int32_t signo;             /* crash: the signal */
    int32_t pad;
    uint64_t addr;             /* crash: the faulting address */
    uint64_t at[4];            /* where the guard's params, state, in, out copies start (0: not fenced) */
    uint64_t size[4];          /* their sizes, bytes: an inaccessible page follows each */
} bc_user_watch;

typedef struct {
    int (*init)(const void *params, void *state); /* the user's adapters */
    bc_ctrl_step_fn step;
    const void *params;    /* what they receive */
    void *state;
    bc_ctrl_in *in;        /* the guard's copy of the measurements (NULL: pass the runner's own) */
    bc_ctrl_out *out;      /* the guard's output (NULL: the runner's own) */
    bc_user_watch *watch;  /* progress and faults (never NULL) */
    int32_t stop;          /* set by a callback that failed: end the run at this sample */
    int32_t pad;
    int64_t k;             /* samples stepped so far */
    void *jump;            /* the jmp_buf of the bc_user_run in progress (NULL outside one) */
} bc_user_guard;

/* Call the user's init once (watch->k = -1). Returns its code, or BC_ERR_PARAM for a NULL guard. */
int bc_user_init(bc_user_guard *g);

/* The runner's step (bc_ctrl_step_fn): state is the bc_user_guard, params unused. */
void bc_user_step(const void *params, void *state, const bc_ctrl_in *in, bc_ctrl_out *out);

/* Check an output against the contract (step 3 above); 0, or the BC_USER_AT_* of the first violation with its
 * index and value. */
int bc_user_check(const bc_ctrl_out *out, int32_t *index, double *value);

/* bc_sim_run with the guard able to end the run: BC_USER_STOPPED if it did (g->watch says why), else bc_sim_run's
 * code. */
int bc_user_run(const bc_sim_config *cfg, bc_sim_state *s, const bc_sim_inputs *in, int64_t n, bc_trace_row *rows,
                int64_t rows_cap, int64_t *rows_written, bc_user_guard *g);

/* Crash handlers writing to w (see above). BC_OK, or BC_ERR_PARAM where signals are not available. */
int bc_user_arm(bc_user_watch *w);

/* Page protection for the guard's fences: mode 0 no access, 1 read only, 2 read and write. BC_OK or BC_ERR_PARAM. */
int bc_user_protect(void *addr, uint64_t len, int32_t mode);

/* The page size (bytes), or 0 where unknown. */
int64_t bc_user_page(void);

#endif /* BC_USERGUARD_H */
