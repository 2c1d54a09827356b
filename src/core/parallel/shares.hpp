// Work cut into a fixed number of shares, so that what a share holds and where its results go
// never depend on the threads, done by whatever threads OpenMP gives the region. It may give fewer
// than asked (OMP_THREAD_LIMIT, OMP_DYNAMIC, or a caller already inside a parallel region, whose
// nested regions get one thread): handing share t to thread t would then leave shares undone —
// points missing from an index, segments from the crossing search (issue 34's session found it).
#pragma once

#include <omp.h>

namespace toposimp::parallel {

// Inside `#pragma omp parallel`: calls work(share) for each of the shares [0, shares) this
// thread takes, every share by exactly one thread of the team.
template <class Work>
void for_my_shares(int shares, Work&& work) {
    for (int share = omp_get_thread_num(); share < shares; share += omp_get_num_threads()) work(share);
}

}  // namespace toposimp::parallel
