// The threads behind the shim's oneTBB loops in the threaded WebAssembly build (web/CMakeLists.txt,
// atmo_mt; Emscripten's pthreads, which need a cross-origin isolated page). In the single-threaded
// build (no __EMSCRIPTEN_PTHREADS__) there is no pool: every loop runs on the calling thread.
// tests/web_shim/thread_pool_test.cc builds it natively with ATMO_WEB_SHIM_THREADS=N (N threads).
//
// One pool of min(cores, 8) - 1 threads, made on first use from Emscripten's prewarmed workers
// (-sPTHREAD_POOL_SIZE, the same count: a thread beyond them would start only after the caller
// returned to its event loop). A loop's chunks go to the pool and to the caller, which waits for
// all of them; a loop started inside a chunk runs on its thread, in order (atmo's nested loops are
// small). An exception from a chunk reaches the caller after every chunk has ended.
#pragma once

#if defined(__EMSCRIPTEN_PTHREADS__) || defined(ATMO_WEB_SHIM_THREADS)
#define ATMO_WEB_SHIM_POOL 1
#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>
#endif

namespace oneapi::tbb::detail {

#if defined(ATMO_WEB_SHIM_POOL)

class ThreadPool {
 public:
  static ThreadPool& Get() {
    static ThreadPool pool;
    return pool;
  }

  // The threads a loop runs on: the pool's and the caller.
  int size() const { return static_cast<int>(workers_.size()) + 1; }

  // 0 outside the pool (the caller), 1..size() - 1 on its threads.
  static int& ThreadIndex() {
    thread_local int index = 0;
    return index;
  }

  // task(k) for k in [0, count), on the pool and the calling thread; returns when all have run.
  void Run(int count, const std::function<void(int)>& task) {
    if (count <= 0) return;
    if (workers_.empty() || count == 1 || InsideLoop()) {
      for (int k = 0; k < count; ++k) task(k);
      return;
    }
    std::lock_guard<std::mutex> one_loop(run_mutex_);
    {
      // A pool thread that woke for the previous loop after its last chunk may still be leaving.
      std::unique_lock<std::mutex> lock(mutex_);
      finished_.wait(lock, [this] { return active_ == 0; });
      task_ = &task;
      count_ = count;
      next_.store(0);
      done_ = 0;
      error_ = nullptr;
      ++generation_;
    }
    wake_.notify_all();
    InsideLoop() = true;
    Work();
    InsideLoop() = false;
    std::unique_lock<std::mutex> lock(mutex_);
    finished_.wait(lock, [this] { return done_ == count_ && active_ == 0; });
    task_ = nullptr;
    if (error_) std::rethrow_exception(error_);
  }

  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

 private:
  ThreadPool() {
#if defined(ATMO_WEB_SHIM_THREADS)
    const int threads = ATMO_WEB_SHIM_THREADS - 1;
#else
    const int threads = std::clamp(static_cast<int>(std::thread::hardware_concurrency()), 1, 8) - 1;
#endif
    for (int i = 0; i < threads; ++i) workers_.emplace_back([this, i] { Serve(i + 1); });
  }

  ~ThreadPool() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    for (std::thread& worker : workers_) worker.join();
  }

  static bool& InsideLoop() {
    thread_local bool inside = false;
    return inside;
  }

  void Serve(int index) {
    ThreadIndex() = index;
    InsideLoop() = true;
    unsigned seen = 0;
    for (;;) {
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
        if (stop_) return;
        seen = generation_;
        ++active_;
      }
      Work();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        --active_;
      }
      finished_.notify_all();
    }
  }

  // Takes chunks until none is left.
  void Work() {
    for (;;) {
      const int k = next_.fetch_add(1);
      if (k >= count_) return;
      try {
        (*task_)(k);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!error_) error_ = std::current_exception();
      }
      std::lock_guard<std::mutex> lock(mutex_);
      if (++done_ == count_) finished_.notify_all();
    }
  }

  std::vector<std::thread> workers_;
  std::mutex run_mutex_;  // one loop at a time
  std::mutex mutex_;
  std::condition_variable wake_, finished_;
  const std::function<void(int)>* task_ = nullptr;
  int count_ = 0;
  std::atomic<int> next_{0};
  int done_ = 0;
  int active_ = 0;  // pool threads inside Work()
  unsigned generation_ = 0;
  bool stop_ = false;
  std::exception_ptr error_;
};

inline int Concurrency() { return ThreadPool::Get().size(); }
inline int ThreadIndex() { return ThreadPool::ThreadIndex(); }
inline void Run(int count, const std::function<void(int)>& task) { ThreadPool::Get().Run(count, task); }

#else

inline int Concurrency() { return 1; }
inline int ThreadIndex() { return 0; }
template <typename Task>
void Run(int count, const Task& task) {
  for (int k = 0; k < count; ++k) task(k);
}

#endif

}  // namespace oneapi::tbb::detail
