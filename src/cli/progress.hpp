// Progress of a long run, on the error stream. Two forms:
// - on a terminal: one line, rewritten in place, at most ten times a second;
// - with --progress (for GUIs and wrappers such as the QGIS provider): plain lines
//   `PROGRESS <percent> <phase>`, one when a phase starts (percent 0) and one each time the whole
//   percent of the phase changes, whatever the stream is.
// Nothing at all otherwise (pipes, logs) or with --quiet. An in-process caller (the Python module)
// may take the same reports as calls instead: (phase, share done 0…1), at each phase's start and
// each whole percent.
#pragma once

#include <chrono>
#include <functional>
#include <ostream>
#include <string>

namespace toposimp::cli {

enum class ProgressStyle { none, terminal, lines };

// The style for a run: --progress wins; else a terminal gets the rewritten line unless --quiet.
inline ProgressStyle progress_style(bool progress_lines, bool err_is_terminal, bool quiet) {
    if (progress_lines) return ProgressStyle::lines;
    return err_is_terminal && !quiet ? ProgressStyle::terminal : ProgressStyle::none;
}

using ProgressCallback = std::function<void(const std::string& phase, double done)>;

class Progress {
public:
    Progress(std::ostream& err, ProgressStyle style, ProgressCallback callback = {})
        : err_(err), style_(style), callback_(std::move(callback)) {}
    ~Progress() { done(); }
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    void phase(const std::string& name) {
        phase_ = name;
        last_ = {};
        called_ = -1;
        percent_ = -1;
        call(0);
        if (style_ == ProgressStyle::lines) {
            show_line(0);
        } else {
            show(-1);
        }
    }

    // `share` of the current phase done (0…1). Safe to call often.
    void update(double share) {
        call(share);
        if (style_ == ProgressStyle::lines) {
            show_line(static_cast<int>(share * 100));
            return;
        }
        const auto now = std::chrono::steady_clock::now();
        if (now - last_ < std::chrono::milliseconds(100)) return;
        last_ = now;
        show(share);
    }

    // Clears the terminal line (the line form has nothing to clear).
    void done() {
        if (style_ != ProgressStyle::terminal || !shown_) return;
        err_ << "\r\033[K" << std::flush;
        shown_ = false;
    }

private:
    void call(double share) {
        if (!callback_) return;
        const int percent = static_cast<int>(share * 100);
        if (percent == called_) return;
        called_ = percent;
        callback_(phase_, share < 0 ? 0.0 : share > 1 ? 1.0 : share);
    }

    void show(double share) {
        if (style_ != ProgressStyle::terminal) return;
        err_ << "\r\033[Ktoposimp: " << phase_;
        if (share >= 0) err_ << ' ' << static_cast<int>(share * 100) << '%';
        err_ << std::flush;
        shown_ = true;
    }

    void show_line(int percent) {
        percent = percent < 0 ? 0 : percent > 100 ? 100 : percent;
        if (percent == percent_) return;
        percent_ = percent;
        err_ << "PROGRESS " << percent << ' ' << phase_ << '\n' << std::flush;
    }

    std::ostream& err_;
    ProgressStyle style_;
    ProgressCallback callback_;
    int called_ = -1;  // the percent last passed to callback_
    bool shown_ = false;
    int percent_ = -1;
    std::string phase_;
    std::chrono::steady_clock::time_point last_{};
};

}  // namespace toposimp::cli
