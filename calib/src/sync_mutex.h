#pragma once
// A std::mutex with Clang thread-safety annotations (libstdc++'s std::mutex has none), so that
// -Wthread-safety checks which members of the sync buffer are touched without its lock.
// Private to rigcal_calib; could move to a shared header if other modules want it.

#include <mutex>

#if defined(__clang__)
#define RIGCAL_THREAD_ANNOTATION(x) __attribute__((x))
#else
#define RIGCAL_THREAD_ANNOTATION(x)
#endif
#define RIGCAL_CAPABILITY(name) RIGCAL_THREAD_ANNOTATION(capability(name))
#define RIGCAL_SCOPED_CAPABILITY RIGCAL_THREAD_ANNOTATION(scoped_lockable)
#define RIGCAL_GUARDED_BY(mu) RIGCAL_THREAD_ANNOTATION(guarded_by(mu))
#define RIGCAL_REQUIRES(...) RIGCAL_THREAD_ANNOTATION(requires_capability(__VA_ARGS__))
#define RIGCAL_ACQUIRE(...) RIGCAL_THREAD_ANNOTATION(acquire_capability(__VA_ARGS__))
#define RIGCAL_RELEASE(...) RIGCAL_THREAD_ANNOTATION(release_capability(__VA_ARGS__))
#define RIGCAL_EXCLUDES(...) RIGCAL_THREAD_ANNOTATION(locks_excluded(__VA_ARGS__))

namespace rigcal {

class RIGCAL_CAPABILITY("mutex") SyncMutex {
 public:
  void Lock() RIGCAL_ACQUIRE() { mutex_.lock(); }
  void Unlock() RIGCAL_RELEASE() { mutex_.unlock(); }
  std::mutex& native() { return mutex_; }

 private:
  std::mutex mutex_;
};

// Holds a SyncMutex for its lifetime.
class RIGCAL_SCOPED_CAPABILITY SyncLock {
 public:
  explicit SyncLock(SyncMutex& mutex) RIGCAL_ACQUIRE(mutex) : lock_(mutex.native()) {}
  ~SyncLock() RIGCAL_RELEASE() {}
  SyncLock(const SyncLock&) = delete;
  SyncLock& operator=(const SyncLock&) = delete;

  // For std::condition_variable::wait*, which releases the mutex while waiting and holds it
  // again when it returns.
  std::unique_lock<std::mutex>& native() { return lock_; }

 private:
  std::unique_lock<std::mutex> lock_;
};

}  // namespace rigcal
