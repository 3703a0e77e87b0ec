/* SUNDIALS CVODE's BDF (variable order 1-5, Newton with a dense difference-quotient
 * Jacobian) on the scene `host-sim simulate --method reference-bdf` runs: the reference
 * device in model.md §4's dimensionless form (restated as in scene.py), from the
 * pre-stretch at rest, output at host-sim's sample times.
 *
 * Usage: cvode_scene BIAS_V AC_V DRIVE_HZ DAMPING_NS DURATION_S STEP_S TOLERANCE RUNS
 * Prints one JSON object: the final stretch, steps, and the best and mean solve time, s. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
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

static int rhs(sunrealtype t, N_Vector y, N_Vector dy, void *data) {
    const Drive *d = data;
    double l = NV_Ith_S(y, 0), v = NV_Ith_S(y, 1);
    double passive = ((L1A + L1B) * L1P - L1A * l) / L1B;
    double volts = d->bias + d->ac * sin(d->omega * t);
    NV_Ith_S(dy, 0) = v;
    NV_Ith_S(dy, 1) = s1(passive) - s1(l) + volts * volts * l * L2P * L2P - d->damping * v;
    return 0;
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char **argv) {
    if (argc != 9) {
        fprintf(stderr, "usage: %s BIAS AC HZ DAMPING DURATION STEP TOL RUNS\n", argv[0]);
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
    double best = INFINITY, total = 0.0, final_stretch = NAN;
    long steps = 0;
    for (int run = 0; run < runs; run++) {
        double started = now();
        SUNContext ctx;
        SUNContext_Create(NULL, &ctx);
        N_Vector y = N_VNew_Serial(2, ctx);
        NV_Ith_S(y, 0) = L1P;
        NV_Ith_S(y, 1) = 0.0;
        void *mem = CVodeCreate(CV_BDF, ctx);
        CVodeInit(mem, rhs, 0.0, y);
        CVodeSStolerances(mem, tol, tol);
        CVodeSetUserData(mem, &d);
        CVodeSetMaxNumSteps(mem, 100000000);
        SUNMatrix a = SUNDenseMatrix(2, 2, ctx);
        SUNLinearSolver ls = SUNLinSol_Dense(y, a, ctx);
        CVodeSetLinearSolver(mem, ls, a);
        double t = 0.0;
        for (long k = 1; k <= count; k++) {
            double tout = (k == count ? duration : k * step) * scale;
            if (CVode(mem, tout, y, &t, CV_NORMAL) < 0) {
                fprintf(stderr, "CVode failed at tau = %g\n", t);
                return 1;
            }
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
    printf("{\"final_stretch\": %.17g, \"samples\": %ld, \"steps\": %ld, \"best_seconds\": %.9g, "
           "\"mean_seconds\": %.9g}\n", final_stretch, count + 1, steps, best, total / runs);
    return 0;
}
