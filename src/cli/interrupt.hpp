// Ctrl-C, `kill`, a closed terminal or a cancelled QGIS task must not leave a half-written output
// behind. The executable calls this first thing: SIGINT, SIGTERM and SIGHUP are blocked in every
// thread and taken by one thread that removes the staging folders of the outputs being written
// (io::OutputFile::abandon_all) and then ends the process by the same signal, so the caller sees
// it was interrupted (exit status 128 + the signal in a shell). Not used by in-process callers
// (tests) of cli::run.
#pragma once

namespace toposimp::cli {

void clean_up_on_interrupt();

}  // namespace toposimp::cli
