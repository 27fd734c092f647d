// SPDX-License-Identifier: Apache-2.0
#pragma once
// Clang thread-safety annotations and an annotated mutex: which mutex guards which member, and
// which function needs it, written in the code and checked by clang's -Wthread-safety
// (ctest -L threads runs tests/architecture/thread_safety_check.sh over every threaded source).
// libstdc++'s std::mutex carries no annotations, hence Mutex and MutexLock. GCC ignores them.
//
// Use:
//   mutable Mutex mutex_;
//   std::deque<T> items_ RIGCAL_GUARDED_BY(mutex_);
//   void DropOldest() RIGCAL_REQUIRES(mutex_);  // the caller holds mutex_
//   void Push(T v) RIGCAL_EXCLUDES(mutex_) { MutexLock lock(mutex_); ... }
// Waiting on a std::condition_variable: a loop around MutexLock::Wait / WaitUntil, with the
// condition written in the loop (the analysis cannot see into a predicate lambda):
//   MutexLock lock(mutex_);
//   while (items_.empty() && !stopped_) lock.Wait(ready_);
// (std::condition_variable::wait(lock, pred) is exactly this loop.)

#include <chrono>
#include <condition_variable>
#include <mutex>

#if defined(__clang__)
#define RIGCAL_THREAD_ANNOTATION(x) __attribute__((x))
#else
#define RIGCAL_THREAD_ANNOTATION(x)
#endif

// A type that is a lock (Mutex).
#define RIGCAL_CAPABILITY(name) RIGCAL_THREAD_ANNOTATION(capability(name))
// An RAII type that holds a lock for its lifetime (MutexLock).
#define RIGCAL_SCOPED_CAPABILITY RIGCAL_THREAD_ANNOTATION(scoped_lockable)
// The member may be read or written only with `mu` held.
#define RIGCAL_GUARDED_BY(mu) RIGCAL_THREAD_ANNOTATION(guarded_by(mu))
// What the pointer member points to may be accessed only with `mu` held.
#define RIGCAL_PT_GUARDED_BY(mu) RIGCAL_THREAD_ANNOTATION(pt_guarded_by(mu))
// Lock order: this mutex is taken before / after the listed ones.
#define RIGCAL_ACQUIRED_BEFORE(...) RIGCAL_THREAD_ANNOTATION(acquired_before(__VA_ARGS__))
#define RIGCAL_ACQUIRED_AFTER(...) RIGCAL_THREAD_ANNOTATION(acquired_after(__VA_ARGS__))
// The function must be called with the listed mutexes held.
#define RIGCAL_REQUIRES(...) RIGCAL_THREAD_ANNOTATION(requires_capability(__VA_ARGS__))
// The function takes / releases the listed mutexes (no argument: `this`).
#define RIGCAL_ACQUIRE(...) RIGCAL_THREAD_ANNOTATION(acquire_capability(__VA_ARGS__))
#define RIGCAL_RELEASE(...) RIGCAL_THREAD_ANNOTATION(release_capability(__VA_ARGS__))
// The function takes the mutex when it returns `result` (true or false).
#define RIGCAL_TRY_ACQUIRE(...) RIGCAL_THREAD_ANNOTATION(try_acquire_capability(__VA_ARGS__))
// The function must be called WITHOUT the listed mutexes held (it takes them itself).
#define RIGCAL_EXCLUDES(...) RIGCAL_THREAD_ANNOTATION(locks_excluded(__VA_ARGS__))
// The function checks at run time that the mutex is held; the analysis assumes it afterwards.
#define RIGCAL_ASSERT_CAPABILITY(mu) RIGCAL_THREAD_ANNOTATION(assert_capability(mu))
// The function returns a reference to the mutex `mu`.
#define RIGCAL_RETURN_CAPABILITY(mu) RIGCAL_THREAD_ANNOTATION(lock_returned(mu))
// Turns the analysis off for one function. Every use says why.
#define RIGCAL_NO_THREAD_SAFETY_ANALYSIS RIGCAL_THREAD_ANNOTATION(no_thread_safety_analysis)

namespace rigcal {

// A std::mutex the analysis knows. Lock it with MutexLock; Lock/Unlock are for the rare code
// that cannot use a scope.
class RIGCAL_CAPABILITY("mutex") Mutex {
 public:
  Mutex() = default;
  Mutex(const Mutex&) = delete;
  Mutex& operator=(const Mutex&) = delete;

  void Lock() RIGCAL_ACQUIRE() { mutex_.lock(); }
  void Unlock() RIGCAL_RELEASE() { mutex_.unlock(); }

 private:
  friend class MutexLock;
  std::mutex mutex_;
};

// Holds a Mutex from construction to destruction (or to Unlock), and waits on condition
// variables with it.
class RIGCAL_SCOPED_CAPABILITY MutexLock {
 public:
  explicit MutexLock(Mutex& mutex) RIGCAL_ACQUIRE(mutex) : lock_(mutex.mutex_) {}
  ~MutexLock() RIGCAL_RELEASE() {}
  MutexLock(const MutexLock&) = delete;
  MutexLock& operator=(const MutexLock&) = delete;

  // Releases the mutex before the scope ends / takes it again.
  void Unlock() RIGCAL_RELEASE() { lock_.unlock(); }
  void Lock() RIGCAL_ACQUIRE() { lock_.lock(); }

  // Releases the mutex, blocks until `cv` is notified (or wakes spuriously), and holds the
  // mutex again when it returns: call it in a loop that tests the condition.
  void Wait(std::condition_variable& cv) { cv.wait(lock_); }
  // As Wait, but returns std::cv_status::timeout once `deadline` has passed.
  template <typename Clock, typename Duration>
  std::cv_status WaitUntil(std::condition_variable& cv,
                           const std::chrono::time_point<Clock, Duration>& deadline) {
    return cv.wait_until(lock_, deadline);
  }

 private:
  std::unique_lock<std::mutex> lock_;
};

}  // namespace rigcal
