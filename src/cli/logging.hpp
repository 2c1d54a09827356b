// A spdlog logger that writes to the run's error stream (one per run, so in-process runs in
// tests do not share state).
#pragma once

#include <spdlog/logger.h>
#include <spdlog/sinks/ostream_sink.h>

#include <memory>
#include <ostream>

namespace toposimp::cli {

inline std::shared_ptr<spdlog::logger> make_logger(std::ostream& err, int verbosity, bool quiet) {
    auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(err, true);
    sink->set_pattern("toposimp: %^%l%$: %v");
    auto logger = std::make_shared<spdlog::logger>("toposimp", sink);
    if (quiet) {
        logger->set_level(spdlog::level::err);
    } else if (verbosity >= 2) {
        logger->set_level(spdlog::level::trace);
    } else if (verbosity == 1) {
        logger->set_level(spdlog::level::debug);
    } else {
        logger->set_level(spdlog::level::info);
    }
    return logger;
}

}  // namespace toposimp::cli
