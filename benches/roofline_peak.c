/*
 * The machine's ceilings for benches/roofline.py, on one core:
 *   roofline_peak fma          GFLOP/s of independent fused multiply-add chains at the widest
 *                              vector width the build targets (AVX-512: 16 f32 lanes)
 *   roofline_peak issue        vector instructions per ns: independent adds and multiplies,
 *                              alternating (the rate the floating-point pipes issue them)
 *   roofline_peak triad BYTES  GB/s of a[i] = b[i] + s c[i] over three f32 arrays of BYTES in
 *                              all: 16 B an element, the read that allocates a's lines
 *                              counted (STREAM counts 12)
 * Each prints one number, the median of 7 timed repetitions after one untimed.
 * Build on the machine it measures: gcc -O3 -march=native -o roofline_peak roofline_peak.c
 */
#define _POSIX_C_SOURCE 200809L
#include <immintrin.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#if defined(__AVX512F__)
typedef __m512 vec;
#define LANES 16
#define SET1 _mm512_set1_ps
#define FMA _mm512_fmadd_ps
#define ADD _mm512_add_ps
#define MUL _mm512_mul_ps
#define SUM(v) _mm512_reduce_add_ps(v)
#elif defined(__AVX2__) && defined(__FMA__)
typedef __m256 vec;
#define LANES 8
#define SET1 _mm256_set1_ps
#define FMA _mm256_fmadd_ps
#define ADD _mm256_add_ps
#define MUL _mm256_mul_ps
static float SUM(__m256 v)
{
    float f[8];
    _mm256_storeu_ps(f, v);
    return f[0] + f[1] + f[2] + f[3] + f[4] + f[5] + f[6] + f[7];
}
#else
#error "roofline_peak needs AVX2 and FMA at least"
#endif

/* An empty asm that "changes" a register: the compiler keeps every chain as written. */
#define KEEP(x) __asm__ volatile("" : "+v"(x))
#define REPS 7

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static volatile float sink;

/* The chains as named variables (an array of vectors stays in memory once an asm touches
 * it): X applied to 0..11. */
#define CHAINS 12
#define EACH(X) X(0) X(1) X(2) X(3) X(4) X(5) X(6) X(7) X(8) X(9) X(10) X(11)
#define DECLARE(k) vec acc##k = SET1((float)k);
#define TOTAL(k) +SUM(acc##k)
#define FMA_STEP(k) acc##k = FMA(acc##k, a, b); KEEP(acc##k);
#define MIX_STEP(k) acc##k = (k & 1) ? MUL(acc##k, a) : ADD(acc##k, b); KEEP(acc##k);

/* FMA chains: CHAINS accumulators, each acc = acc * a + b; returns flops per ns. */
static double fma_rate(long iters)
{
    vec a = SET1(0.999999f), b = SET1(1e-7f);
    EACH(DECLARE)
    double t0 = now();
    for (long i = 0; i < iters; i++) {
        EACH(FMA_STEP)
    }
    double t = now() - t0;
    sink = 0 EACH(TOTAL);
    return 2.0 * LANES * CHAINS * iters / (t * 1e9);
}

/* Independent adds and multiplies, alternating; returns vector instructions per ns. */
static double issue_rate(long iters)
{
    vec a = SET1(0.999999f), b = SET1(1e-7f);
    EACH(DECLARE)
    double t0 = now();
    for (long i = 0; i < iters; i++) {
        EACH(MIX_STEP)
    }
    double t = now() - t0;
    sink = 0 EACH(TOTAL);
    return (double)CHAINS * iters / (t * 1e9);
}

static double triad_rate(size_t n, float *a, const float *b, const float *c)
{
    double t0 = now();
    for (size_t i = 0; i < n; i++)
        a[i] = b[i] + 3.0f * c[i];
    double t = now() - t0;
    sink = a[n / 2];
    return 16.0 * n / (t * 1e9);
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: roofline_peak fma|issue|triad BYTES\n");
        return 2;
    }
    double r[REPS + 1];
    if (strcmp(argv[1], "fma") == 0 || strcmp(argv[1], "issue") == 0) {
        int is_fma = argv[1][0] == 'f';
        for (int k = 0; k <= REPS; k++)
            r[k] = is_fma ? fma_rate(20000000) : issue_rate(20000000);
    } else if (strcmp(argv[1], "triad") == 0 && argc == 3) {
        size_t n = strtoull(argv[2], NULL, 10) / 12;
        size_t size = (n * 4 + 127) / 64 * 64; /* aligned_alloc: a multiple of 64 */
        float *a = aligned_alloc(64, size), *b = aligned_alloc(64, size),
              *c = aligned_alloc(64, size);
        if (!a || !b || !c)
            return 1;
        for (size_t i = 0; i < n; i++)
            a[i] = 0, b[i] = 1, c[i] = 2;
        /* Each repetition a gigabyte or more: passes enough for about 10 ms. */
        int passes = (int)(1 + 1e9 / (12.0 * n));
        for (int k = 0; k <= REPS; k++) {
            double sum = 0;
            for (int p = 0; p < passes; p++)
                sum += triad_rate(n, a, b, c);
            r[k] = sum / passes;
        }
    } else {
        fprintf(stderr, "usage: roofline_peak fma|issue|triad BYTES\n");
        return 2;
    }
    qsort(r + 1, REPS, sizeof r[0], cmp); /* the first repetition is the warm-up */
    printf("%.3f\n", r[1 + REPS / 2]);
    return 0;
}
