// A bounded queue that keeps the newest items: a producer never waits, and when the queue is full
// the oldest item is pushed out and handed back so the caller can count and report it. The
// mapping node puts received clouds in it; its insertion thread takes them out.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>
#include <optional>
#include <stdexcept>

namespace evidential_octomap {

template <typename T>
class LatestQueue {
 public:
  explicit LatestQueue(size_t capacity) : capacity_(capacity) {
    if (capacity_ == 0) throw std::invalid_argument("queue capacity must be >= 1");
  }

  // Adds `item`; returns the oldest item if it had to make room for it (the dropped one).
  std::optional<T> push(T item) {
    std::optional<T> dropped;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (items_.size() == capacity_) {
        dropped = std::move(items_.front());
        items_.pop_front();
      }
      items_.push_back(std::move(item));
    }
    ready_.notify_one();
    return dropped;
  }

  // Waits for the oldest item; std::nullopt once the queue is closed (items left are discarded).
  std::optional<T> pop() {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait(lock, [&] { return closed_ || !items_.empty(); });
    if (closed_) return std::nullopt;
    T item = std::move(items_.front());
    items_.pop_front();
    return item;
  }

  // Waits at most `timeout` for an item (or the close); true when pop() would not wait.
  template <class Duration>
  bool waitFor(Duration timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    return ready_.wait_for(lock, timeout, [&] { return closed_ || !items_.empty(); });
  }

  // Wakes every waiting pop(), which then returns std::nullopt; later pushes are kept but
  // never popped.
  void close() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
    }
    ready_.notify_all();
  }

  size_t size() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return items_.size();
  }
  size_t capacity() const { return capacity_; }

 private:
  const size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<T> items_;
  bool closed_ = false;
};

}  // namespace evidential_octomap
