// The commands' one error guard: a command's work runs inside it, and what it throws becomes a
// message naming the file, layer and feature (the exception's own text) and an exit status.
#pragma once

#include "cli/cli.hpp"
#include "io/common/errors.hpp"

#include <spdlog/logger.h>

#include <new>
#include <string>

namespace toposimp::cli {

// A usage error found once the work has started (the command's options do not fit together or
// with the input): exit status 2, as for bad input. In-process callers get it as it is.
struct UsageError {
    std::string message;
};

// A topology or validation failure (`--validate` found violations): exit status 1, no output.
struct TopologyFailure {
    std::string message;
};

// Runs `work` (returning an exit status): bad input or an unwritable output (InputError,
// OutputError) and running out of memory exit 2, a TopologyFailure exits 1, each with its message.
template <class Work>
int guarded(spdlog::logger& log, Work&& work) {
    try {
        return work();
    } catch (const io::InputError& error) {
        log.error("{}", error.what());
    } catch (const io::OutputError& error) {
        log.error("{}", error.what());
    } catch (const UsageError& error) {
        log.error("{}", error.message);
    } catch (const TopologyFailure& failure) {
        log.error("{}", failure.message);
        return kTopologyFailure;
    } catch (const std::bad_alloc&) {
        log.error("out of memory");
    }
    return kUsageError;
}

}  // namespace toposimp::cli
