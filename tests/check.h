/*
 * A minimal test harness: CHECK records a failure with its location and goes
 * on, so one run reports every broken expectation; TEST_EXIT gives ctest the
 * verdict. A test that cannot run here calls test_skip (exit 77, registered
 * as SKIP_RETURN_CODE).
 */
#ifndef WSG_TEST_CHECK_H
#define WSG_TEST_CHECK_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static int check_failures;
static int check_count;

#define CHECK(cond)                                                           \
    do {                                                                      \
        check_count++;                                                        \
        if (!(cond)) {                                                        \
            check_failures++;                                                 \
            fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__,  \
                    #cond);                                                   \
        }                                                                     \
    } while (0)

#define CHECK_EQ(a, b)                                                        \
    do {                                                                      \
        long long check_a_ = (long long)(a), check_b_ = (long long)(b);       \
        check_count++;                                                        \
        if (check_a_ != check_b_) {                                           \
            check_failures++;                                                 \
            fprintf(stderr,                                                   \
                    "%s:%d: CHECK_EQ failed: %s == %s (%lld != %lld)\n",      \
                    __FILE__, __LINE__, #a, #b, check_a_, check_b_);          \
        }                                                                     \
    } while (0)

#define CHECK_NEAR(a, b, tol)                                                 \
    do {                                                                      \
        double check_a_ = (double)(a), check_b_ = (double)(b);                \
        check_count++;                                                        \
        if (!(fabs(check_a_ - check_b_) <= (tol))) {                          \
            check_failures++;                                                 \
            fprintf(stderr, "%s:%d: CHECK_NEAR failed: %s ~ %s (%g vs %g)\n", \
                    __FILE__, __LINE__, #a, #b, check_a_, check_b_);          \
        }                                                                     \
    } while (0)

/* Stop the test at once (a precondition for the rest failed). */
#define REQUIRE(cond)                                                         \
    do {                                                                      \
        int require_ok_ = (cond) ? 1 : 0; /* evaluated once */                \
        CHECK(require_ok_ &&#cond);                                           \
        if (!require_ok_)                                                     \
            exit(1);                                                          \
    } while (0)

static inline void test_skip(const char *why)
{
    printf("SKIP: %s\n", why);
    exit(77);
}

static inline int test_exit(void)
{
    printf("%d checks, %d failed\n", check_count, check_failures);
    if (check_count == 0)
        return 1; /* a test that checked nothing has not passed */
    return check_failures ? 1 : 0;
}
#define TEST_EXIT() return test_exit()

#endif
