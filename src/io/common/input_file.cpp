#include "io/common/input_file.hpp"

#include "io/common/errors.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace toposimp::io {

void refuse_non_files(const std::string& path) {
    std::error_code error;
    const std::filesystem::file_status status = std::filesystem::status(path, error);
    if (error) return;
    switch (status.type()) {
        case std::filesystem::file_type::directory: throw InputError(path + ": is a directory, not a file");
        case std::filesystem::file_type::character:
        case std::filesystem::file_type::block: throw InputError(path + ": is a device, not a file");
        default: return;
    }
}

std::uint64_t stream_limit() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), size = ::sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || size <= 0) return std::uint64_t{1} << 34;
    return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(size) / 2;
}

std::string read_file(const std::string& path) {
    refuse_non_files(path);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path + ": cannot open: " + std::strerror(errno));
    // In big chunks (a character at a time took a tenth of a second on a 2 M-triangle PLY).
    std::string data;
    std::size_t size = 0;
    // At once when the size is known (a regular file): no growing, no copying.
    std::error_code error;
    const std::uintmax_t known = std::filesystem::is_regular_file(path, error) ? std::filesystem::file_size(path, error) : 0;
    if (!error && known > 0) {
        data.resize(known);
        in.read(data.data(), static_cast<std::streamsize>(known));
        size = static_cast<std::size_t>(in.gcount());
        if (size < known || in.peek() != std::char_traits<char>::eof()) {
            in.clear();  // (it changed meanwhile: read on as for a stream)
        } else {
            return data;
        }
    }
    const std::uint64_t limit = stream_limit();
    for (;;) {
        if (size > limit) throw InputError(path + ": more than half of this machine's memory; not read");
        data.resize(size + (std::size_t{1} << 22));
        in.read(data.data() + size, static_cast<std::streamsize>(data.size() - size));
        size += static_cast<std::size_t>(in.gcount());
        if (!in) break;
    }
    if (in.bad()) throw InputError(path + ": read error");
    data.resize(size);
    return data;
}

}  // namespace toposimp::io
