// The model a calibration writes (CalibrateOptions::write_grid_converged). When the grid limits
// the fit, the estimates are what makes THIS grid reproduce the recordings: part of each is the
// grid's error (docs/calibration.md, "Grid refinement"). Recordings of a canal, or of a simulator
// that resolves it finely, are better reproduced by the grid-converged estimates
// (discretisation.hpp grid_converged) on a finer grid. Measured on an independent-like truth of the
// lab (1600 cells, minmod θ = 1.5, both gates' laws regularised near zero head) calibrated on 400
// cells (the default set, with downstream_zero_head_mm): on five other recordings the
// residual fell 4.9-20.9x with the grid-converged estimates on 800 cells, 7.9-27.5x on 1600.
#pragma once

#include <vector>

#include "calibration/calibrate.hpp"
#include "calibration/parameters.hpp"
#include "calibration/replay.hpp"
#include "core/recording.hpp"

namespace canalsim::calibration {

// Puts in c.calibrated the grid-converged estimates on twice the cells of every pool when that
// model's weighted cost on the fitted recordings is below the fit's own (its estimates on its own
// grid), or on four times the cells when the doubling still cut the cost below 0.7 of the cost
// before it (the grid, not the physics, still limiting) and four times fit better still. Not the
// estimates on twice the cells, though those may fit the fitted recordings a little better (they
// are nearer that grid's optimum): they carry the grid error of the coarser grid into the finer
// one, and on the truth above they left 4.5x on op1* where the grid-converged ones left 5.7x
// (their cost on the four fitted recordings 0.0167 against 0.0171). Then restates the
// "after" figures of every recording, fitted and validation, for it, and says so in
// c.written_note. Leaves c as it is when the grid check did not run or the grid-converged
// estimates equal the estimates. `parameters`, `replay`: those of the fit.
void write_grid_converged(Calibration& c, const std::vector<Parameter>& parameters, const std::vector<Recording>& recordings,
                          const std::vector<Recording>& validation, const ReplayOptions& replay, int threads);

}  // namespace canalsim::calibration
