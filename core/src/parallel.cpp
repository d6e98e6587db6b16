#include "afterglow/core/parallel.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace afterglow {

namespace {
std::atomic<int> gThreads{0};
}

void setThreadCount(int threads) { gThreads = std::max(0, threads); }

int threadCount() {
  int t = gThreads.load();
  if (t > 0) return t;
  return std::max(1u, std::thread::hardware_concurrency());
}

void parallelForBlocks(size_t count,
                       const std::function<void(size_t, size_t, int)>& body, size_t grain) {
  if (count == 0) return;
  const int threads = int(std::min<size_t>(threadCount(), count));
  if (grain == 0) grain = std::max<size_t>(1, count / (size_t(threads) * 8));
  if (threads <= 1 || count <= grain) {
    body(0, count, 0);
    return;
  }
  // Blocks are claimed dynamically for load balance; each block's work only depends on its
  // range, so results are the same whichever thread runs it.
  std::atomic<size_t> next{0};
  std::exception_ptr error;
  std::mutex errorMutex;
  auto worker = [&](int threadIndex) {
    try {
      for (;;) {
        size_t begin = next.fetch_add(grain);
        if (begin >= count) break;
        body(begin, std::min(count, begin + grain), threadIndex);
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(errorMutex);
      if (!error) error = std::current_exception();
      next = count;
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(threads - 1);
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker, t);
  worker(0);
  for (auto& th : pool) th.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace afterglow
