// Stopping a long run from outside (Ctrl-C in Python, a cancelled task): the caller owns a flag
// and sets it from anywhere (a signal handler too); the engine reads it now and then and, once it
// is set, stops and throws Cancelled on the calling thread — never from inside a parallel region.
// Nothing is returned then: the run's input is as it was given (or, for an in-place mesh,
// documented where it applies).
#pragma once

#include <atomic>
#include <exception>

namespace toposimp {

class Cancelled : public std::exception {
public:
    const char* what() const noexcept override { return "cancelled"; }
};

// Has the caller asked to stop? (A null flag never does.)
inline bool cancel_requested(const std::atomic<bool>* flag) {
    return flag != nullptr && flag->load(std::memory_order_relaxed);
}

// Throws Cancelled if the caller has asked to stop.
inline void stop_if_cancelled(const std::atomic<bool>* flag) {
    if (cancel_requested(flag)) throw Cancelled();
}

}  // namespace toposimp
