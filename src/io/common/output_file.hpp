// Output that appears only on success: everything is written into a private temporary folder
// beside the destination and moved into place by commit(); if commit() is never reached the
// folder is removed, so a failed run leaves no half-written file behind.
// /vsistdout/ is handled the same way: written to a temporary file, then copied to stdout.
#pragma once

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>

namespace toposimp::io {

class OutputFile {
public:
    // Refuses (OutputError) if `destination` exists and `overwrite` is false. Output for
    // /vsistdout/ (or "-") is copied to `stdout_stream` on commit.
    OutputFile(std::string destination, bool overwrite, std::ostream* stdout_stream);
    ~OutputFile();
    OutputFile(const OutputFile&) = delete;
    OutputFile& operator=(const OutputFile&) = delete;

    // Where to write: a path with the destination's file name inside the temporary folder.
    const std::string& staging_path() const { return staging_path_; }
    const std::string& destination() const { return destination_; }
    bool to_stdout() const { return to_stdout_; }

    // Moves every file written into the staging folder to the destination folder (a Shapefile's
    // .shp/.shx/.dbf/.prj/.cpg together). `remove_existing` deletes an existing destination
    // first (e.g. with the GDAL driver, which knows a format's side files).
    void commit(const std::function<void(const std::string&)>& remove_existing = {});

    // The constructor's checks alone (an existing output without `overwrite`, a missing folder),
    // for commands that open the output only after long work: they fail before it.
    static void check_destination(const std::string& destination, bool overwrite);

    // For an interrupted process (SIGINT, SIGTERM, SIGHUP; called from a thread that waits for
    // them): removes the staging folder of every OutputFile still open and keeps any commit from
    // starting afterwards, so the caller can end the process with nothing half-written left.
    // A commit already under way finishes first.
    static void abandon_all();

private:
    std::string destination_;
    std::filesystem::path staging_dir_;
    std::string staging_path_;
    bool overwrite_ = false;
    bool to_stdout_ = false;
    bool committed_ = false;
    std::ostream* stdout_stream_ = nullptr;
};

}  // namespace toposimp::io
