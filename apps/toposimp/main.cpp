#include "cli/cli.hpp"

#include <unistd.h>

#include <iostream>

int main(int argc, char** argv) {
    std::ios::sync_with_stdio(false);
    toposimp::cli::Context context{std::cout, std::cerr, ::isatty(STDERR_FILENO) == 1};
    return toposimp::cli::run({argv + 1, argv + argc}, context);
}
