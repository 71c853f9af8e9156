// Many independent closed-loop runs advanced in parallel on std::threads (Python's
// adparm.simulate_batch). The runs share nothing: each owns its settings, state and recording, so
// every run gives bit-for-bit the numbers it gives alone, whatever the number of threads. Each
// advance() starts the threads, which take runs from a shared counter, advance each by up to
// max_steps and stop; between calls the caller can report progress or stop.
#pragma once

#include <atomic>
#include <chrono>
#include <exception>
#include <string>
#include <thread>
#include <vector>

#include "adparm/simulation.hpp"

namespace adparm {

template <class Run>
class Batch {
 public:
  explicit Batch(const std::vector<Settings>& settings) {
    runs_.reserve(settings.size());
    for (std::size_t i = 0; i < settings.size(); ++i) {
      try {
        runs_.emplace_back(settings[i]);
      } catch (const std::invalid_argument& error) {
        throw std::invalid_argument("settings[" + std::to_string(i) + "]: " + error.what());
      }
    }
    seconds_.assign(runs_.size(), 0.0);
  }

  std::size_t size() const { return runs_.size(); }
  Run& operator[](std::size_t i) { return runs_.at(i); }
  const Run& operator[](std::size_t i) const { return runs_.at(i); }
  // Wall time spent advancing run i, in seconds (on whichever thread ran it).
  double seconds(std::size_t i) const { return seconds_.at(i); }

  bool running() const {
    for (const Run& run : runs_)
      if (run.status() == RunStatus::running) return true;
    return false;
  }

  // Advances every running run by up to max_steps steps on `threads` threads (1: in the calling
  // thread). Returns whether any run is still running.
  bool advance(long max_steps, int threads) {
    if (threads < 1) throw std::invalid_argument("threads: must be >= 1");
    std::atomic<std::size_t> next{0};
    const std::size_t workers = std::min<std::size_t>(threads, runs_.size());
    if (workers <= 1) {
      work(next, max_steps);
      return running();
    }
    std::vector<std::exception_ptr> errors(workers);
    std::vector<std::thread> pool;
    pool.reserve(workers);
    try {
      for (std::size_t w = 0; w < workers; ++w) {
        pool.emplace_back([this, &next, &errors, w, max_steps] {
          try {
            work(next, max_steps);
          } catch (...) {
            errors[w] = std::current_exception();
          }
        });
      }
    } catch (...) {  // a thread could not start: finish with those that did, then report
      for (std::thread& thread : pool) thread.join();
      throw;
    }
    for (std::thread& thread : pool) thread.join();
    for (const std::exception_ptr& error : errors)
      if (error) std::rethrow_exception(error);
    return running();
  }

 private:
  void work(std::atomic<std::size_t>& next, long max_steps) {
    for (std::size_t i = next++; i < runs_.size(); i = next++) {
      if (runs_[i].status() != RunStatus::running) continue;
      const auto start = std::chrono::steady_clock::now();
      runs_[i].advance(max_steps);
      seconds_[i] +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
  }

  std::vector<Run> runs_;
  std::vector<double> seconds_;
};

}  // namespace adparm
