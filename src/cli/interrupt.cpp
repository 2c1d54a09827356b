#include "cli/interrupt.hpp"

#include "io/common/output_file.hpp"

#include <pthread.h>
#include <unistd.h>

#include <csignal>
#include <thread>

namespace toposimp::cli {

void clean_up_on_interrupt() {
    sigset_t signals;
    sigemptyset(&signals);
    for (const int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&signals, sig);
    // Threads started later (OpenMP's, GDAL's) inherit the mask, so only the waiter gets them.
    if (pthread_sigmask(SIG_BLOCK, &signals, nullptr) != 0) return;
    std::thread([signals] {
        int sig = 0;
        if (sigwait(&signals, &sig) != 0) return;
        io::OutputFile::abandon_all();
        // End as the signal would have: default action, unblocked here, raised on this thread.
        std::signal(sig, SIG_DFL);
        sigset_t only;
        sigemptyset(&only);
        sigaddset(&only, sig);
        pthread_sigmask(SIG_UNBLOCK, &only, nullptr);
        std::raise(sig);
        _exit(128 + sig);
    }).detach();
}

}  // namespace toposimp::cli
