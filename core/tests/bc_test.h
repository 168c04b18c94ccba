/* bc_test.h - minimal host test harness: CHECK counts, the summary line is 'N passed, N failed'. */
#ifndef BC_TEST_H
#define BC_TEST_H

#include <math.h>
#include <stdio.h>

static int bc_test_pass = 0;
static int bc_test_fail = 0;

#define CHECK(cond, ...)                                                   \
    do {                                                                   \
        if (cond) {                                                        \
            ++bc_test_pass;                                                \
        } else {                                                           \
            ++bc_test_fail;                                                \
            printf("FAIL %s:%d: ", __FILE__, __LINE__);                    \
            printf(__VA_ARGS__);                                           \
            printf("\n");                                                  \
        }                                                                  \
    } while (0)

#define CHECK_NEAR(a, b, tol, what)                                                                   \
    CHECK(fabs((double)(a) - (double)(b)) <= (double)(tol), "%s: %.12g vs %.12g (tol %.3g)", what, \
          (double)(a), (double)(b), (double)(tol))

static int bc_test_summary(const char *name)
{
    printf("%s: %d passed, %d failed\n", name, bc_test_pass, bc_test_fail);
    return bc_test_fail == 0 ? 0 : 1;
}

#endif /* BC_TEST_H */
