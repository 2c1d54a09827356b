#include "io/common/output_file.hpp"

#include "io/common/errors.hpp"

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <mutex>
#include <ostream>
#include <random>
#include <vector>

namespace fs = std::filesystem;

namespace toposimp::io {
namespace {

fs::path make_private_dir(const fs::path& parent, const std::string& stem) {
    std::random_device entropy;
    for (int attempt = 0; attempt < 100; ++attempt) {
        const fs::path dir = parent / ("." + stem + ".toposimp-" + std::to_string(::getpid()) + "-" +
                                       std::to_string(entropy() % 1000000));
        std::error_code error;
        if (fs::create_directory(dir, error)) return dir;
        if (error) throw OutputError("cannot create a temporary folder in '" + parent.string() + "': " + error.message());
    }
    throw OutputError("cannot create a temporary folder in '" + parent.string() + "'");
}

// Staging folders of the OutputFiles alive now, for abandon_all(). The mutex is also held by
// every commit, so a commit and an abandon never interleave.
std::mutex& registry_mutex() {
    static std::mutex mutex;
    return mutex;
}

std::vector<fs::path>& registry() {
    static std::vector<fs::path> folders;
    return folders;
}

void enroll(const fs::path& dir) {
    const std::lock_guard lock(registry_mutex());
    registry().push_back(dir);
}

void withdraw(const fs::path& dir) {
    const std::lock_guard lock(registry_mutex());
    std::erase(registry(), dir);
}

}  // namespace

void OutputFile::abandon_all() {
    registry_mutex().lock();  // never unlocked: the process is about to end
    for (const fs::path& dir : registry()) {
        std::error_code ignored;
        fs::remove_all(dir, ignored);
    }
    registry().clear();
}

namespace {

bool is_stdout(const std::string& destination) {
    return destination == "/vsistdout/" || destination == "/vsistdout" || destination == "-";
}

}  // namespace

void OutputFile::check_destination(const std::string& destination, bool overwrite) {
    if (is_stdout(destination)) return;
    const fs::path target(destination);
    if (target.filename().empty()) throw OutputError("output '" + destination + "' is a folder, not a file name");
    std::error_code error;
    const fs::file_status status = fs::status(target, error);
    if (fs::exists(status)) {
        // Only files are replaced: --overwrite on a device or a folder would have put a file in
        // its place (issue 29: as root, -o /dev/null --overwrite replaced /dev/null).
        if (!fs::is_regular_file(status)) {
            throw OutputError("output '" + destination + "' is " + (fs::is_directory(status) ? "a folder" : "not a regular file (a device?)") +
                              "; toposimp writes and replaces files only (for standard output, use -o /vsistdout/)");
        }
        if (!overwrite) throw OutputError("output '" + destination + "' exists; pass --overwrite to replace it");
    }
    const fs::path parent = target.parent_path().empty() ? fs::path(".") : target.parent_path();
    if (!fs::is_directory(parent, error)) throw OutputError("output folder '" + parent.string() + "' does not exist");
}

OutputFile::OutputFile(std::string destination, bool overwrite, std::ostream* stdout_stream)
    : destination_(std::move(destination)), overwrite_(overwrite), stdout_stream_(stdout_stream) {
    to_stdout_ = is_stdout(destination_);
    fs::path target = to_stdout_ ? fs::path("stdout") : fs::path(destination_);
    if (!to_stdout_) {
        check_destination(destination_, overwrite_);
        const fs::path parent = target.parent_path().empty() ? fs::path(".") : target.parent_path();
        staging_dir_ = make_private_dir(parent, target.filename().string());
    } else {
        staging_dir_ = make_private_dir(fs::temp_directory_path(), "stdout");
    }
    staging_path_ = (staging_dir_ / target.filename()).string();
    enroll(staging_dir_);
}

OutputFile::~OutputFile() {
    withdraw(staging_dir_);
    std::error_code ignored;
    fs::remove_all(staging_dir_, ignored);
}

void OutputFile::commit(const std::function<void(const std::string&)>& remove_existing) {
    if (committed_) return;
    const std::lock_guard lock(registry_mutex());
    if (to_stdout_) {
        std::ifstream in(staging_path_, std::ios::binary);
        if (!in) throw OutputError("cannot read back the output written for stdout");
        if (stdout_stream_ == nullptr) throw OutputError("no standard output to write to");
        *stdout_stream_ << in.rdbuf();
        stdout_stream_->flush();
        if (!*stdout_stream_) throw OutputError("cannot write to stdout");
        committed_ = true;
        return;
    }
    const fs::path target(destination_);
    std::error_code error;
    if (fs::exists(target, error)) {
        if (!overwrite_) throw OutputError("output '" + destination_ + "' appeared while writing; not replaced");
        if (remove_existing) remove_existing(destination_);
        if (fs::exists(target, error)) fs::remove(target, error);
    }
    const fs::path parent = target.parent_path().empty() ? fs::path(".") : target.parent_path();
    for (const auto& entry : fs::directory_iterator(staging_dir_)) {
        fs::rename(entry.path(), parent / entry.path().filename(), error);
        if (error) throw OutputError("cannot move '" + entry.path().string() + "' into place: " + error.message());
    }
    committed_ = true;
}

}  // namespace toposimp::io
