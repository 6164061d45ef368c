/* Forward sensitivities of an RK4 run whose stage Jacobians are taken at the step ends.
 *
 * The C twin of cable_ocp.control.linearisation.propagate_sensitivities for the closed loop's
 * stage Jacobians (ErrorLinearisation with stage_jacobians="ends"): stage 1 takes the Jacobian
 * at the step's start, stages 2 and 3 the mean of the two ends, stage 4 the one at its end.
 * Written by hand because the loop is a few dozen products of a (size x nx) block by (nx x nx)
 * matrices per step: numpy spends most of its time calling, CasADi's generated mtimes decodes
 * sparsity at every product (cable_ocp/control/step_end_tangent.py gives the figures). NX, the
 * state size, is fixed when compiling, so that a row of a slope is summed in registers.
 *
 * Layouts (C order, doubles):
 *   points   (steps + 1, NX + 3, NX): the transposed Jacobians [d x'/d x, d x'/d w]^T at the RK4
 *            points, as the compiled point Jacobians write them;
 *   winch    (steps, 9, size): D_k, the winch parameters to the step's nine winch inputs (row
 *            3 c + d: stage-input column c, derivative d);
 *   out      (steps + 1, size, kept): the first `kept` state components of S_k transposed,
 *            S_0 = 0;
 *   work     4 size NX + (NX + 3) NX doubles of scratch.
 */
#include <string.h>

#ifndef NX
#error "compile with -DNX=<state size>"
#endif
#define STAGES 4
#define WINCH_INPUTS 3
#define WIDTH (NX + WINCH_INPUTS)

/* slope row r = sum_i point[r, i] jacobian[i] + sum_c winch_rows[c, r] jacobian[NX + c] */
static void stage_slope(int size, const double *restrict jacobian,
                        const double *restrict winch_rows, const double *restrict point,
                        double *restrict slope) {
    for (int r = 0; r < size; ++r) {
        double row[NX] = {0.0};
        const double *restrict at = point + (size_t)r * NX;
        for (int i = 0; i < WIDTH; ++i) {
            const double weight = i < NX ? at[i] : winch_rows[(size_t)(i - NX) * size + r];
            if (weight == 0.0) {
                continue; /* a parameter not yet touched, or a state it does not move */
            }
            const double *restrict column = jacobian + (size_t)i * NX;
            for (int j = 0; j < NX; ++j) {
                row[j] += weight * column[j];
            }
        }
        memcpy(slope + (size_t)r * NX, row, sizeof row);
    }
}

void step_end_tangent(int steps, int size, int kept, double step,
                      const double *restrict points, const double *restrict winch,
                      double *restrict out, double *restrict work) {
    const size_t block = (size_t)size * NX, width = (size_t)WIDTH * NX;
    double *current = work, *point = work + block, *slope = work + 2 * block;
    double *sum = work + 3 * block, *mean = work + 4 * block;
    const double advance[STAGES] = {0.5 * step, 0.5 * step, step, 0.0};
    const double weight[STAGES] = {1.0, 2.0, 2.0, 1.0};
    const int column[STAGES] = {0, 1, 1, 2};
    memset(current, 0, sizeof(double) * block);
    memset(out, 0, sizeof(double) * (size_t)size * kept);
    for (int k = 0; k < steps; ++k) {
        const double *start = points + (size_t)k * width, *end = start + width;
        const double *rows = winch + (size_t)k * 3 * WINCH_INPUTS * size;
        for (size_t i = 0; i < width; ++i) {
            mean[i] = 0.5 * (start[i] + end[i]);
        }
        const double *jacobian[STAGES] = {start, mean, mean, end};
        memcpy(point, current, sizeof(double) * block);
        memset(sum, 0, sizeof(double) * block);
        for (int s = 0; s < STAGES; ++s) {
            stage_slope(size, jacobian[s], rows + (size_t)WINCH_INPUTS * column[s] * size, point,
                        slope);
            for (size_t i = 0; i < block; ++i) {
                sum[i] += weight[s] * slope[i];
                point[i] = current[i] + advance[s] * slope[i];
            }
        }
        double *target = out + (size_t)(k + 1) * size * kept;
        for (int r = 0; r < size; ++r) {
            double *row = current + (size_t)r * NX;
            const double *added = sum + (size_t)r * NX;
            for (int j = 0; j < NX; ++j) {
                row[j] += step / 6.0 * added[j];
            }
            memcpy(target + (size_t)r * kept, row, sizeof(double) * (size_t)kept);
        }
    }
}
