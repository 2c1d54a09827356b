// The toposimp command line as a library: tests call run() in-process.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

namespace toposimp::cli {

// Exit statuses (DESIGN.md): 0 ok, 1 topology or validation failure, 2 usage or input error.
enum ExitCode : int { kOk = 0, kTopologyFailure = 1, kUsageError = 2 };

struct Context {
    std::ostream& out;                // results: --json, help text
    std::ostream& err;                // messages
    bool err_is_terminal = false;     // print the one-line summary even without -v
};

// Runs `toposimp ARGS...` (args excludes the program name) and returns the exit status.
int run(const std::vector<std::string>& args, Context& context);

}  // namespace toposimp::cli
