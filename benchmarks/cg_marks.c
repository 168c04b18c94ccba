/*
 * cg_marks.c - callgrind client requests for Python (benchmarks/cost.py loads it with ctypes).
 *
 * The cost runs start valgrind with --instr-atstart=no: Python's imports run uninstrumented (about four times
 * faster than under full instrumentation) and nothing before cg_start() is counted. cg_start() turns the
 * instrumentation on right before the measured call, cg_stop() off after it, so the profile holds that call only.
 * Outside valgrind the requests are no-ops.
 */
#include <valgrind/callgrind.h>

void cg_start(void)
{
    CALLGRIND_START_INSTRUMENTATION;
    CALLGRIND_ZERO_STATS;
}

void cg_stop(void) { CALLGRIND_STOP_INSTRUMENTATION; }
