// Rank 0's own worker (RunOptions::rank0 = works): a thread that runs the tasks rank 0's main
// thread gives it, one at a time, while the main thread serves the other ranks (MPI calls stay on
// the main thread: MPI_THREAD_FUNNELED).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>

namespace omma::dist {

template <class Result>
class WorkerThread {
 public:
  explicit WorkerThread(std::function<Result(int64_t)> work)
      : work_(std::move(work)), thread_([this] { loop(); }) {}
  ~WorkerThread() {
    {
      std::lock_guard l(m_);
      stop_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  WorkerThread(const WorkerThread&) = delete;
  WorkerThread& operator=(const WorkerThread&) = delete;
  // Starts task `id` (the previous one must have been collected).
  void assign(int64_t id) {
    {
      std::lock_guard l(m_);
      task_ = id;
      busy_ = true;
    }
    cv_.notify_all();
  }
  bool busy() const { return busy_; }
  // The result of the task, if it finishes within `timeout`.
  std::optional<Result> wait_result(std::chrono::microseconds timeout) {
    std::unique_lock l(m_);
    cv_.wait_for(l, timeout, [&] { return result_.has_value(); });
    std::optional<Result> r;
    r.swap(result_);
    if (r) busy_ = false;
    return r;
  }

 private:
  void loop() {
    for (;;) {
      int64_t id;
      {
        std::unique_lock l(m_);
        cv_.wait(l, [&] { return stop_ || task_ >= 0; });
        if (stop_) return;
        id = task_;
        task_ = -1;
      }
      Result r = work_(id);
      {
        std::lock_guard l(m_);
        result_ = std::move(r);
      }
      cv_.notify_all();
    }
  }
  std::function<Result(int64_t)> work_;
  std::mutex m_;
  std::condition_variable cv_;
  int64_t task_ = -1;
  bool stop_ = false, busy_ = false;
  std::optional<Result> result_;
  std::thread thread_;  // last: starts once the members above exist
};

}  // namespace omma::dist
