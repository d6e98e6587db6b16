// parallelFor: the one way afterglow spreads work over threads. Work items are split into
// contiguous blocks handed out in order; results must not depend on which thread ran which
// block (seed random numbers from the item index, never from the thread).
#pragma once

#include <cstddef>
#include <functional>

namespace afterglow {

// Threads used by parallelFor. 0 (the default) means std::thread::hardware_concurrency().
void setThreadCount(int threads);
int threadCount();

// Calls body(begin, end, threadIndex) for consecutive blocks of [0, count). threadIndex is in
// [0, threadCount()) and lets a caller keep per-thread scratch space. grain is the block size;
// 0 picks one that gives each thread several blocks.
void parallelForBlocks(size_t count,
                       const std::function<void(size_t begin, size_t end, int threadIndex)>& body,
                       size_t grain = 0);

// Calls body(i) for every i in [0, count).
template <class F>
void parallelFor(size_t count, F&& body, size_t grain = 0) {
  parallelForBlocks(
      count, [&](size_t begin, size_t end, int) {
        for (size_t i = begin; i < end; ++i) body(i);
      },
      grain);
}

// parallelForBlocks as the runtime takes it (runtime::ParallelFor: body(begin, end) over
// [0, count), one item a block), for the solver and the gather maps.
inline std::function<void(size_t, const std::function<void(size_t, size_t)>&)> blockRanges() {
  return [](size_t count, const std::function<void(size_t, size_t)>& body) {
    parallelForBlocks(count, [&](size_t begin, size_t end, int) { body(begin, end); }, 1);
  };
}

}  // namespace afterglow
