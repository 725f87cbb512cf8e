// One parallel loop for every module: trials of a blind test, recordings of a fit, candidate
// effects of a diagnosis, perturbed simulations of a calibration. Hand-written on std::thread
// rather than oneTBB: the loops are a few dozen coarse tasks (each a simulation or a fit of
// milliseconds to seconds), where a work queue of one atomic counter is all the scheduling needed,
// and the user's --threads must be the exact number of threads used.
#pragma once

#include <cstddef>
#include <functional>

namespace canalsim {

// Runs body(i) for every i in [0, count) on min(threads, count) threads (the calling thread is one
// of them; threads <= 1 runs in order on the calling thread). Indices are handed out one at a time
// in increasing order, so tasks of uneven length balance. Bodies must write only their own slot of
// any shared output. If bodies throw, every index still runs and the exception of the lowest
// failing index is rethrown afterwards, so the error reported does not depend on scheduling.
void parallel_for(std::size_t count, int threads, const std::function<void(std::size_t)>& body);

}  // namespace canalsim
