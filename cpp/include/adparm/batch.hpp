// Many independent closed-loop runs on a pool of std::threads (Python's adparm.simulate_batch,
// adparm.simulate and adparm.sweep). The runs share nothing: each owns its settings, state and
// recording, so every run gives bit-for-bit the numbers it gives alone, whatever the number of
// threads. start() launches the workers; each takes the next run from a shared queue, builds it,
// runs it to the end and takes the next one: no barrier between threads. The caller only polls:
// wait() returns the runs finished since the last call, steps_done() the progress; stop() makes
// every worker return within one step (RunControl), and take() hands a run over to the caller,
// which frees it. A window bounds the runs built but not yet taken, so a stream of many runs holds
// only a few recordings at a time. Every run is built once. The runs read their URDF files through
// one UrdfArmCache: runs sharing a file share its parsed model (const; each run has its own
// Pinocchio Data).
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "adparm/simulation.hpp"
#include "adparm/urdf_loop_arm.hpp"

namespace adparm {

template <class Run>
class Batch {
 public:
  // Checks every run's settings by building it, naming the first invalid one. The first `window`
  // runs stay built for the workers (built once); a run beyond the window is built again when a
  // worker reaches it (its URDF is not read again), so that at most `window` recordings are held.
  // The runs read their URDFs through `urdfs` (a new cache if none is given).
  explicit Batch(std::vector<Settings> settings,
                 std::size_t window = std::numeric_limits<std::size_t>::max(),
                 std::shared_ptr<UrdfArmCache> urdfs = nullptr)
      : settings_(std::move(settings)),
        urdfs_(urdfs ? std::move(urdfs) : std::make_shared<UrdfArmCache>()),
        runs_(settings_.size()),
        seconds_(settings_.size(), 0.0),
        steps_(new StepCounter[settings_.size()]),
        totals_(settings_.size(), 0),
        window_(window) {
    if (window < 1) throw std::invalid_argument("window: must be >= 1");
    for (std::size_t i = 0; i < settings_.size(); ++i) {
      const auto start = std::chrono::steady_clock::now();
      try {
        auto run = std::make_unique<Run>(settings_[i], *urdfs_);
        totals_[i] = run->steps();
        if (i < window_) {
          runs_[i] = std::move(run);
          ++built_;
          seconds_[i] =
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        }
      } catch (const std::invalid_argument& error) {
        throw std::invalid_argument("settings[" + std::to_string(i) + "]: " + error.what());
      }
    }
  }
  Batch(const Batch&) = delete;
  Batch& operator=(const Batch&) = delete;
  ~Batch() { stop(); }

  std::size_t size() const { return settings_.size(); }
  // Steps of all runs together, and those taken so far (readable while the workers run).
  long total_steps() const {
    long total = 0;
    for (long steps : totals_) total += steps;
    return total;
  }
  long steps_done() const {
    long done = 0;
    for (std::size_t i = 0; i < size(); ++i)
      done += steps_[i].value.load(std::memory_order_relaxed);
    return done;
  }

  // Starts `threads` workers (at most one per run). At most `window` runs are built and not yet
  // taken at any time (a worker waits for take() before building more).
  void start(int threads) {
    if (threads < 1) throw std::invalid_argument("threads: must be >= 1");
    if (started_) throw std::logic_error("Batch: already started");
    started_ = true;
    const std::size_t workers = std::min<std::size_t>(threads, size());
    workers_ = workers;
    pool_.reserve(workers);
    try {
      for (std::size_t w = 0; w < workers; ++w) pool_.emplace_back([this] { work(); });
    } catch (...) {  // a thread could not start: stop those that did, then report
      stop();
      throw;
    }
    if (workers == 0) finished_all_ = true;
  }

  // Waits up to `seconds` for a run to end; returns the indices of the runs that ended since the
  // last call (in the order they ended). Rethrows an exception a worker met.
  std::vector<std::size_t> wait(double seconds) {
    std::unique_lock<std::mutex> lock(mutex_);
    const auto ready = [this] { return !ended_.empty() || finished_all_ || error_ != nullptr; };
    if (seconds > 0) changed_.wait_for(lock, std::chrono::duration<double>(seconds), ready);
    if (error_ != nullptr) {
      std::exception_ptr error = error_;
      lock.unlock();
      stop();
      std::rethrow_exception(error);
    }
    std::vector<std::size_t> out(ended_.begin(), ended_.end());
    ended_.clear();
    return out;
  }

  // Whether every run has ended (or the batch was stopped) and every ending was reported by wait().
  bool done() {
    std::lock_guard<std::mutex> lock(mutex_);
    return finished_all_ && ended_.empty();
  }

  // Asks every worker to return (within one step of its run) and joins them. Runs not ended stay
  // as they are (status running); runs never started are built by take().
  void stop() {
    stop_.store(true);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      finished_all_ = true;
    }
    room_.notify_all();
    for (std::thread& thread : pool_)
      if (thread.joinable()) thread.join();
    pool_.clear();
  }

  // Hands run i over to the caller (which frees it): ended, stopped part-way, or built now if it
  // never started. Only for a run that wait() reported, or after stop().
  std::unique_ptr<Run> take(std::size_t i) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (i >= size()) throw std::out_of_range("index: out of range");
    if (taken_.size() < size()) taken_.assign(size(), false);
    if (taken_[i]) throw std::logic_error("Batch: run " + std::to_string(i) + " already taken");
    std::unique_ptr<Run> run = std::move(runs_[i]);
    if (!run) {
      if (!finished_all_ && claimed_ > i)
        throw std::logic_error("Batch: run " + std::to_string(i) + " is still running");
      run = std::make_unique<Run>(settings_[i], *urdfs_);
    } else {
      --built_;
    }
    taken_[i] = true;
    lock.unlock();
    room_.notify_all();
    return run;
  }

  // Wall time spent building and advancing run i, in seconds (on whichever thread ran it).
  double seconds(std::size_t i) const { return seconds_.at(i); }

  // Runs everything to the end on `threads` threads (the C++ bench's and tests' entry point).
  std::vector<std::unique_ptr<Run>> run_all(int threads) {
    start(threads);
    while (!done()) wait(1.0);
    wait(0.0);
    std::vector<std::unique_ptr<Run>> out;
    for (std::size_t i = 0; i < size(); ++i) out.push_back(take(i));
    return out;
  }

 private:
  void work() {
    try {
      while (!stop_.load()) {
        std::size_t i;
        std::unique_ptr<Run> run;  // built by the constructor, or built here
        {
          std::unique_lock<std::mutex> lock(mutex_);
          room_.wait(lock, [this] {
            return stop_.load() || claimed_ >= size() || runs_[claimed_] || built_ < window_;
          });
          if (stop_.load() || claimed_ >= size()) break;
          i = claimed_++;
          run = std::move(runs_[i]);
          if (!run) ++built_;
        }
        const auto start = std::chrono::steady_clock::now();
        if (!run) run = std::make_unique<Run>(settings_[i], *urdfs_);
        run->advance(std::numeric_limits<long>::max(), RunControl{&stop_, &steps_[i].value});
        steps_[i].value.store(run->step(), std::memory_order_relaxed);
        seconds_[i] +=
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        const bool ended = run->status() != RunStatus::running;
        std::lock_guard<std::mutex> lock(mutex_);
        runs_[i] = std::move(run);
        if (ended) ended_.push_back(i);
        changed_.notify_all();
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!error_) error_ = std::current_exception();
      stop_.store(true);
      changed_.notify_all();
      room_.notify_all();
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (++workers_done_ == workers_) finished_all_ = true;
    changed_.notify_all();
  }

  std::vector<Settings> settings_;
  std::shared_ptr<UrdfArmCache> urdfs_;  // the runs' URDF arms, each file read once (thread-safe)
  std::vector<std::unique_ptr<Run>> runs_;  // built, not yet started or ended and not yet taken
  std::vector<double> seconds_;
  // One cache line per run's step counter: the workers write theirs at every step, and counters
  // sharing a line would bounce it between the cores.
  struct alignas(64) StepCounter {
    std::atomic<long> value{0};
  };
  std::unique_ptr<StepCounter[]> steps_;
  std::vector<long> totals_;
  std::vector<bool> taken_;
  std::vector<std::thread> pool_;
  std::mutex mutex_;
  std::condition_variable changed_;  // a run ended, every worker returned, or an error
  std::condition_variable room_;     // a run was taken, or stop
  std::deque<std::size_t> ended_;
  std::exception_ptr error_;
  std::atomic<bool> stop_{false};
  bool started_ = false;
  bool finished_all_ = false;
  std::size_t claimed_ = 0;  // runs handed to workers
  std::size_t built_ = 0;    // runs built and not yet taken
  std::size_t window_ = 0;
  std::size_t workers_ = 0;
  std::size_t workers_done_ = 0;
};

}  // namespace adparm
