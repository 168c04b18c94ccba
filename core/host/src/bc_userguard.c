/* bc_userguard.c - the guard around a user's controller (bc_userguard.h): progress, output checks, the end of a run
 * at the first violation, crash handlers and page protection for a child process that runs user code. */
#if !defined(_XOPEN_SOURCE) && (defined(__unix__) || defined(__APPLE__))
#define _XOPEN_SOURCE 700 /* POSIX.1-2008 with XSI: sigaction, sigaltstack, mprotect, sysconf */
#endif
#if defined(__APPLE__) && !defined(_DARWIN_C_SOURCE)
#define _DARWIN_C_SOURCE 1 /* sigaltstack, MAP_ANON */
#endif

#include "bldc/bc_userguard.h"

#include <math.h>
#include <setjmp.h>
#include <string.h>

#if defined(__unix__) || defined(__APPLE__)
#define BC_USER_POSIX 1
#include <signal.h>
#include <sys/mman.h>
#include <unistd.h>
#endif

static int finite_d(double v) { return isfinite(v) ? 1 : 0; }

static int leg_check(const bc_leg_cmd *c, int at_mode, int at_duty, int j, int32_t *index, double *value)
{
    int32_t m = c->mode;
    if (m != BC_LEG_OFF && m != BC_LEG_PWM && m != BC_LEG_HIGH && m != BC_LEG_LOW) {
        *index = j;
        *value = (double)m;
        return at_mode;
    }
    double d = (double)c->duty;
    if (!(d >= 0.0 && d <= 1.0)) { /* NaN fails both */
        *index = j;
        *value = d;
        return at_duty;
    }
    return 0;
}

int bc_user_check(const bc_ctrl_out *out, int32_t *index, double *value)
{
    int at;
    for (int j = 0; j < 3; ++j) {
        at = leg_check(&out->leg[j], BC_USER_AT_MODE, BC_USER_AT_DUTY, j, index, value);
        if (at) return at;
    }
    if (out->has_at != 0u && out->has_at != 1u) {
        *index = 0;
        *value = (double)out->has_at;
        return BC_USER_AT_HAS_AT;
    }
    if (out->has_at) {
        double t = (double)out->t_at;
        if (!(finite_d(t) && t >= 0.0)) {
            *index = 0;
            *value = t;
            return BC_USER_AT_T_AT;
        }
        for (int j = 0; j < 3; ++j) {
            at = leg_check(&out->leg_at[j], BC_USER_AT_MODE_AT, BC_USER_AT_DUTY_AT, j, index, value);
            if (at) return at;
        }
    }
    for (int j = 0; j < BC_DIAG_N; ++j) {
        if (!finite_d((double)out->diag[j])) {
            *index = j;
            *value = (double)out->diag[j];
            return BC_USER_AT_DIAG;
        }
    }
    if (!finite_d((double)out->i_hold) || !finite_d((double)out->i_hold_at)) {
        *index = finite_d((double)out->i_hold) ? 1 : 0;
        *value = (double)(*index ? out->i_hold_at : out->i_hold);
        return BC_USER_AT_HOLD;
    }
    return 0;
}

int bc_user_init(bc_user_guard *g)
{
    if (g == 0 || g->watch == 0 || g->init == 0) return BC_ERR_PARAM;
    bc_user_watch *w = g->watch;
    w->k = -1;
    w->entered = w->entered + 1u;
    w->busy = 1;
    int rc = g->init(g->params, g->state);
    w->busy = 0;
    w->done = w->done + 1u;
    g->k = 0;
    return rc;
}

/* The first violation: record it, then end the run (or, outside bc_user_run, leave the legs off). */
static void stop(bc_user_guard *g, bc_ctrl_out *out, int32_t fault, int32_t where, int32_t index, double value)
{
    bc_user_watch *w = g->watch;
    w->fault = fault;
    w->where = where;
    w->index = index;
    w->value = value;
    if (g->jump != 0) longjmp(*(jmp_buf *)g->jump, 1);
    bc_legs_off(out);
    out->has_at = 0u;
}

void bc_user_step(const void *params, void *state, const bc_ctrl_in *in, bc_ctrl_out *out)
{
    bc_user_guard *g = (bc_user_guard *)state;
    bc_user_watch *w = g->watch;
    (void)params;
    const bc_ctrl_in *ui = in;
    bc_ctrl_out *uo = out;
    if (g->in != 0) {
        *g->in = *in;
        ui = g->in;
    }
    if (g->out != 0) {
        memset(g->out, 0, sizeof *g->out); /* as the runner clears its own */
        uo = g->out;
    }
    w->k = g->k;
    w->entered = w->entered + 1u;
    w->busy = 1;
    g->step(g->params, g->state, ui, uo);
    w->busy = 0;
    w->done = w->done + 1u;
    g->k += 1;
    if (uo != out) *out = *uo;
    if (g->stop) {
        stop(g, out, BC_USER_FAULT_STOP, 0, 0, 0.0);
        return;
    }
    if (ui != in && memcmp(ui, in, sizeof *in) != 0) {
        const unsigned char *a = (const unsigned char *)ui, *b = (const unsigned char *)in;
        int32_t j = 0;
        while ((size_t)j < sizeof *in && a[j] == b[j]) ++j;
        stop(g, out, BC_USER_FAULT_INPUT, 0, j, 0.0);
        return;
    }
    int32_t index = 0;
    double value = 0.0;
    int at = bc_user_check(out, &index, &value);
    if (at) stop(g, out, BC_USER_FAULT_OUTPUT, at, index, value);
}

/* Kept apart from bc_user_run so that nothing of the caller's lives across setjmp (C99 7.13.2.1). */
static int run_jumped(bc_user_guard *g)
{
    g->jump = 0;
    return BC_USER_STOPPED;
}

int bc_user_run(const bc_sim_config *cfg, bc_sim_state *s, const bc_sim_inputs *in, int64_t n, bc_trace_row *rows,
                int64_t rows_cap, int64_t *rows_written, bc_user_guard *g)
{
    jmp_buf env;
    if (g == 0 || g->watch == 0) return BC_ERR_PARAM;
    g->jump = &env;
    if (setjmp(env) != 0) return run_jumped(g);
    int rc = bc_sim_run(cfg, s, in, n, rows, rows_cap, rows_written);
    g->jump = 0;
    return rc;
}

#ifdef BC_USER_POSIX

/* The watch of this process's crash handlers: one per process (a signal handler has no other way to it). */
static bc_user_watch *armed;
static unsigned char alt_stack[1 << 16]; /* the handlers' stack: a stack overflow leaves none */

static void on_crash(int sig, siginfo_t *si, void *ctx)
{
    (void)ctx;
    if (armed != 0) {
        armed->signo = sig;
        armed->addr = (uint64_t)(uintptr_t)si->si_addr;
        armed->fault = BC_USER_FAULT_SIGNAL;
    }
    /* SA_RESETHAND restored the default action: returning re-raises the fault (SIGSEGV, SIGBUS, SIGFPE, SIGILL),
     * abort() raises SIGABRT again; raise() covers a signal sent by kill() */
    raise(sig);
}

int bc_user_arm(bc_user_watch *w)
{
    static const int sigs[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};
    if (w == 0) return BC_ERR_PARAM;
    stack_t ss;
    memset(&ss, 0, sizeof ss);
    ss.ss_sp = alt_stack;
    ss.ss_size = sizeof alt_stack;
    if (sigaltstack(&ss, 0) != 0) return BC_ERR_PARAM;
    armed = w;
    for (size_t j = 0; j < sizeof sigs / sizeof sigs[0]; ++j) {
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_sigaction = on_crash;
        sa.sa_flags = (int)(SA_SIGINFO | SA_ONSTACK | SA_RESETHAND); /* glibc: SA_RESETHAND is 0x80000000u */
        sigemptyset(&sa.sa_mask);
        if (sigaction(sigs[j], &sa, 0) != 0) return BC_ERR_PARAM;
    }
    return BC_OK;
}

int bc_user_protect(void *addr, uint64_t len, int32_t mode)
{
    int prot = mode == 0 ? PROT_NONE : (mode == 1 ? PROT_READ : PROT_READ | PROT_WRITE);
    if (addr == 0 || mode < 0 || mode > 2) return BC_ERR_PARAM;
    return mprotect(addr, (size_t)len, prot) == 0 ? BC_OK : BC_ERR_PARAM;
}

int64_t bc_user_page(void)
{
    long n = sysconf(_SC_PAGESIZE);
    return n > 0 ? (int64_t)n : 0;
}

#else

int bc_user_arm(bc_user_watch *w)
{
    (void)w;
    return BC_ERR_PARAM;
}

int bc_user_protect(void *addr, uint64_t len, int32_t mode)
{
    (void)addr;
    (void)len;
    (void)mode;
    return BC_ERR_PARAM;
}

int64_t bc_user_page(void) { return 0; }

#endif
