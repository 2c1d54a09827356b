// What an input path must be before a reader of ours looks at it: a file (or a pipe), not a
// directory or a device, whose bytes fit in memory. /dev/zero behind a mesh name would otherwise
// be read until the machine runs out of memory (issue 29).
#pragma once

#include <cstdint>
#include <string>

namespace toposimp::io {

// InputError if `path` is a directory or a character or block device (a pipe or a regular file
// passes; one that does not exist is left to the reader, which says it cannot open it).
void refuse_non_files(const std::string& path);

// How many bytes a reader may hold of a stream whose size is not known in advance: half the
// machine's memory.
std::uint64_t stream_limit();

// The file's bytes, read in big chunks (at once when its size is known); InputError if it cannot
// be read, is not a file (refuse_non_files) or would take more than stream_limit().
std::string read_file(const std::string& path);

}  // namespace toposimp::io
