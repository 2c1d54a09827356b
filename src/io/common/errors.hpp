// Errors the I/O adapters raise. Each message names the file, the layer and the feature.
#pragma once

#include <stdexcept>
#include <string>

namespace toposimp::io {

// Bad or unreadable input: the CLI reports it and exits with status 2.
class InputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// The output could not be written: the CLI reports it and exits with status 2.
class OutputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

}  // namespace toposimp::io
