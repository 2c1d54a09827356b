// The `toposimp` command. It runs the mesh jobs that need no GDAL (a mesh file in, a mesh file
// out) itself, and hands every other command line to toposimp-gdal, the whole tool, by exec:
// loading GDAL's ~115 shared libraries costs ~50 ms at every start, half of a small mesh job.
// This executable links no GDAL or GEOS (toposimp_mesh_cli has neither; tests/cli/launcher_test.cpp
// checks that a mesh file job loads none).
#include "cli/interrupt.hpp"
#include "cli/mesh_command.hpp"

#include <malloc.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <string_view>
#include <vector>

namespace {

// toposimp-gdal beside this executable (a build tree), or where `cmake --install` puts it
// (TOPOSIMP_GDAL_DIR, relative to the bin folder: ../libexec/toposimp by default).
std::filesystem::path whole_tool() {
    std::error_code error;
    const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
    const std::filesystem::path dir = error ? std::filesystem::path(".") : self.parent_path();
    const std::filesystem::path beside = dir / "toposimp-gdal", installed = dir / TOPOSIMP_GDAL_DIR / "toposimp-gdal";
    return ::access(beside.c_str(), X_OK) == 0 ? beside : installed;
}

constexpr std::string_view kHugePagesTunable = "glibc.malloc.hugetlb";

// Did the user (or an exec of ours) name glibc.malloc.hugetlb in GLIBC_TUNABLES?
bool huge_pages_named() {
    const char* tunables = std::getenv("GLIBC_TUNABLES");
    return tunables != nullptr && std::string_view(tunables).find(kHugePagesTunable) != std::string_view::npos;
}

// The environment jobs run in: this one, with glibc's malloc told to ask for transparent huge
// pages for the heap (the tunable glibc.malloc.hugetlb=1: madvise(MADV_HUGEPAGE) on what it takes
// from the kernel), unless the user set that tunable. Where THP is in `madvise` mode (as on the
// machines we measure on), big arrays otherwise sit on 4 KiB pages: a page fault per 4 KiB and a
// TLB miss on nearly every access at random (on a VM whose page faults were slow: GSHHG at --keep
// 10 % on 2 threads 13 % faster, a 2 M-triangle terrain 18 %; about even when they were fast; the
// same peaks; BENCHMARKS.md). glibc reads tunables when a program starts, so they are set before
// an exec: of toposimp-gdal, or of this program again.
std::vector<std::string> job_environment() {
    constexpr std::string_view kName = "GLIBC_TUNABLES=", kHugePages = "glibc.malloc.hugetlb=1";
    std::vector<std::string> environment;
    bool tunables = false;
    for (char** entry = environ; *entry != nullptr; ++entry) {
        std::string variable = *entry;
        if (variable.starts_with(kName)) {
            tunables = true;
            if (variable.find(kHugePagesTunable) == std::string::npos) {
                variable += variable.size() > kName.size() ? ":" : "";
                variable += kHugePages;
            }
        }
        environment.push_back(std::move(variable));
    }
    if (!tunables) environment.push_back(std::string(kName) + std::string(kHugePages));
    return environment;
}

// Mesh files from this size on are simplified with huge pages (a 2 M-triangle PLY is 50 MB).
constexpr std::uintmax_t kHugePagesFrom = 8u << 20;

// An environment as execve takes it.
std::vector<char*> pointers(std::vector<std::string>& environment) {
    std::vector<char*> envp;
    for (std::string& variable : environment) envp.push_back(variable.data());
    envp.push_back(nullptr);
    return envp;
}

}  // namespace

int main(int argc, char** argv) {
    const std::vector<std::string> args(argv + 1, argv + argc);
    toposimp::cli::MeshCommandOptions options;
    if (!toposimp::cli::parse_mesh_command(args, options) || toposimp::cli::mesh_needs_gdal(options)) {
        const std::filesystem::path tool = whole_tool();
        std::vector<char*> tool_argv{const_cast<char*>(tool.c_str())};
        for (int i = 1; i < argc; ++i) tool_argv.push_back(argv[i]);
        tool_argv.push_back(nullptr);
        std::vector<std::string> environment = job_environment();
        ::execve(tool.c_str(), tool_argv.data(), pointers(environment).data());
        std::cerr << "toposimp: error: cannot run " << tool.string() << ": " << std::strerror(errno)
                  << " (toposimp-gdal, the part of toposimp that reads GIS formats, is not installed there)\n";
        return toposimp::cli::kUsageError;
    }
    std::error_code error;
    if (!huge_pages_named() && std::filesystem::file_size(options.input, error) >= kHugePagesFrom && !error) {
        // (A big mesh job here: this program again, with huge pages; as it is if that fails. A
        // small one is quicker without: an exec and 2 MiB pages zeroed, 5 ms of a 65 ms job.)
        std::vector<std::string> environment = job_environment();
        ::execve("/proc/self/exe", argv, pointers(environment).data());
    }
    // As in toposimp-gdal's main: freed big arrays stay in the heap, not unmapped and faulted
    // in again phase after phase.
    mallopt(M_MMAP_THRESHOLD, 1 << 30);
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
    toposimp::cli::clean_up_on_interrupt();
    std::ios::sync_with_stdio(false);
    toposimp::cli::Context context{std::cout, std::cerr, ::isatty(STDERR_FILENO) == 1};
    return toposimp::cli::run_mesh(options, context, {});
}
