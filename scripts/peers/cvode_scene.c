/* SUNDIALS CVODE's BDF (variable order 1-5, Newton with a dense linear solver and the
 * analytic Jacobian, as host-sim's Radau and BDF have it) on the scene `host-sim simulate`
 * runs: the reference device in model.md §4's dimensionless form (restated as in scene.py),
 * from rest at the pre-stretch or at the bias's equilibrium, output at host-sim's sample times.
 *
 * Usage: cvode_scene BIAS_V AC_V DRIVE_HZ DAMPING_NS DURATION_S STEP_S TOLERANCE RUNS
 *                    [START [SERIES]]
 *   START   prestretch (default) | equilibrium
 *   SERIES  a file to write the stretch at every output time to (float64, raw), last run's
 * Prints one JSON object: the final stretch, steps, and the best and mean solve time, s. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

static const double MU = 45e3, JLIM = 120.0, EPS = 4.7 * 8.8541878128e-12;
static const double RHO = 960.0, H = 1.0e-3, L1A = 20e-3, L1B = 20e-3, L2 = 40e-3;
static const double BAR = 2e-3, L1P = 2.0, L2P = 2.0;

typedef struct { double bias, ac, omega, damping; } Drive;

static double s1(double l) {
    double i1 = l * l + L2P * L2P + 1.0 / (l * l * L2P * L2P);
    return (l - 1.0 / (l * l * l * L2P * L2P)) / (1.0 - (i1 - 3.0) / JLIM);
}

/* ds1/dλ by the quotient rule (scene.py's ds1). */
static double ds1(double l) {
    double i1 = l * l + L2P * L2P + 1.0 / (l * l * L2P * L2P);
    double num = l - 1.0 / (l * l * l * L2P * L2P), den = 1.0 - (i1 - 3.0) / JLIM;
    double dnum = 1.0 + 3.0 / (l * l * l * l * L2P * L2P);
    double dden = -(2.0 * l - 2.0 / (l * l * l * L2P * L2P)) / JLIM;
    return (dnum * den - num * dden) / (den * den);
}

static double passive_of(double l) { return ((L1A + L1B) * L1P - L1A * l) / L1B; }

static double acceleration(double l, double volts) {
    return s1(passive_of(l)) - s1(l) + volts * volts * l * L2P * L2P;
}

static int rhs(sunrealtype t, N_Vector y, N_Vector dy, void *data) {
    const Drive *d = data;
    double l = NV_Ith_S(y, 0), v = NV_Ith_S(y, 1);
    double volts = d->bias + d->ac * sin(d->omega * t);
    NV_Ith_S(dy, 0) = v;
    NV_Ith_S(dy, 1) = acceleration(l, volts) - d->damping * v;
    return 0;
}

static int jac(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix j, void *data, N_Vector t1,
               N_Vector t2, N_Vector t3) {
    const Drive *d = data;
    double l = NV_Ith_S(y, 0), volts = d->bias + d->ac * sin(d->omega * t);
    SM_ELEMENT_D(j, 0, 0) = 0.0;
    SM_ELEMENT_D(j, 0, 1) = 1.0;
    SM_ELEMENT_D(j, 1, 0) = -ds1(passive_of(l)) * L1A / L1B - ds1(l) + volts * volts * L2P * L2P;
    SM_ELEMENT_D(j, 1, 1) = -d->damping;
    return 0;
}

/* The loading branch's stretch at a constant bias: bisection on λ'' = 0 in [λ1p, 3]. */
static double equilibrium(double bias) {
    double low = L1P, high = 3.0;
    for (int i = 0; i < 200; i++) {
        double mid = 0.5 * (low + high);
        if (acceleration(mid, bias) > 0.0) low = mid; else high = mid;
    }
    return 0.5 * (low + high);
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char **argv) {
    if (argc < 9 || argc > 11) {
        fprintf(stderr, "usage: %s BIAS AC HZ DAMPING DURATION STEP TOL RUNS [START [SERIES]]\n",
                argv[0]);
        return 2;
    }
    int from_equilibrium = argc > 9 && strcmp(argv[9], "equilibrium") == 0;
    if (argc > 9 && !from_equilibrium && strcmp(argv[9], "prestretch") != 0) {
        fprintf(stderr, "START is prestretch or equilibrium, not %s\n", argv[9]);
        return 2;
    }
    FILE *series = NULL;
    if (argc > 10 && !(series = fopen(argv[10], "wb"))) {
        perror(argv[10]);
        return 2;
    }
    double bias = atof(argv[1]), ac = atof(argv[2]), hz = atof(argv[3]), c = atof(argv[4]);
    double duration = atof(argv[5]), step = atof(argv[6]), tol = atof(argv[7]);
    int runs = atoi(argv[8]);
    double mass = BAR * L1A + RHO * L2 * H * L1A * (L1A + L1B) / 3.0;
    double scale = sqrt(MU * L2 * H / mass), volts_per_unit = H * sqrt(MU / EPS);
    Drive d = {bias / volts_per_unit, ac / volts_per_unit, 2.0 * M_PI * hz / scale,
               c / (mass * scale)};
    long count = (long)ceil(duration / step * (1.0 - 1e-12));
    double start = from_equilibrium ? equilibrium(d.bias) : L1P;
    double *stretch = malloc((count + 1) * sizeof *stretch);
    double best = INFINITY, total = 0.0, final_stretch = NAN;
    long steps = 0;
    for (int run = 0; run < runs; run++) {
        double started = now();
        SUNContext ctx;
#if SUNDIALS_VERSION_MAJOR >= 7
        SUNContext_Create(SUN_COMM_NULL, &ctx);
#else
        SUNContext_Create(NULL, &ctx);
#endif
        N_Vector y = N_VNew_Serial(2, ctx);
        NV_Ith_S(y, 0) = start;
        NV_Ith_S(y, 1) = 0.0;
        void *mem = CVodeCreate(CV_BDF, ctx);
        CVodeInit(mem, rhs, 0.0, y);
        CVodeSStolerances(mem, tol, tol);
        CVodeSetUserData(mem, &d);
        CVodeSetMaxNumSteps(mem, 100000000);
        SUNMatrix a = SUNDenseMatrix(2, 2, ctx);
        SUNLinearSolver ls = SUNLinSol_Dense(y, a, ctx);
        CVodeSetLinearSolver(mem, ls, a);
        CVodeSetJacFn(mem, jac);
        double t = 0.0;
        stretch[0] = start;
        for (long k = 1; k <= count; k++) {
            double tout = (k == count ? duration : k * step) * scale;
            if (CVode(mem, tout, y, &t, CV_NORMAL) < 0) {
                fprintf(stderr, "CVode failed at tau = %g\n", t);
                return 1;
            }
            stretch[k] = NV_Ith_S(y, 0);
        }
        final_stretch = NV_Ith_S(y, 0);
        CVodeGetNumSteps(mem, &steps);
        CVodeFree(&mem);
        SUNLinSolFree(ls);
        SUNMatDestroy(a);
        N_VDestroy(y);
        SUNContext_Free(&ctx);
        double elapsed = now() - started;
        best = elapsed < best ? elapsed : best;
        total += elapsed;
    }
    if (series) {
        fwrite(stretch, sizeof *stretch, count + 1, series);
        fclose(series);
    }
    free(stretch);
    printf("{\"final_stretch\": %.17g, \"samples\": %ld, \"steps\": %ld, \"best_seconds\": %.9g, "
           "\"mean_seconds\": %.9g}\n", final_stretch, count + 1, steps, best, total / runs);
    return 0;
}
