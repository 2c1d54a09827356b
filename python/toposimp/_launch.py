"""How `python3 -m toposimp.dask` starts: its own process again, with glibc's malloc asking for
transparent huge pages and keeping freed blocks for reuse, before the engine and numpy are loaded.

glibc reads its tunables once, when a process starts, so the command runs itself again with them
(os.execve, the same command line). Python imports this package before it runs toposimp.dask as
the main module, so the package asks here first: restarted later, every run would load the
engine's libraries and numpy twice (0.13 s a run here). Nothing here may import the engine.
"""
import os
import sys

# Interpreter options that take the next argument as their value (python3 --help).
_WITH_VALUE = {"-X", "-W", "--check-hash-based-pycs"}


def huge_pages(tunables):
    """glibc's tunables `tunables` with malloc asking for transparent huge pages for the heap
    (glibc.malloc.hugetlb=1), unless they say otherwise: a map's arrays of hundreds of MB then sit
    on 2 MiB pages where the kernel's THP mode is `madvise` (fewer page faults, fewer TLB misses;
    the toposimp command does the same for its own process). Read by glibc when a process starts:
    set for the worker processes of a LocalCluster started here, and for the command's own process
    by restart_with_huge_pages."""
    if "glibc.malloc.hugetlb" in tunables:
        return tunables
    return tunables + (":" if tunables else "") + "glibc.malloc.hugetlb=1"


# The command's own heap (not its workers'): blocks under 32 MiB from the heap, and the heap's top
# given back to the kernel only past 256 MiB free. A round's tiles are built here group by group
# and pickled for their tasks (blocks of about 10 MiB each on GSHHG), then freed; with glibc's
# defaults they were mapped afresh or trimmed and faulted in again, every page zeroed by the
# kernel each time. GSHHG at 10 % on 2 workers, 8 runs each, alternating: 4.52 -> 4.32 s
# (medians), the same peak memory.
_COMMAND_HEAP = ("glibc.malloc.mmap_threshold=33554432", "glibc.malloc.trim_threshold=268435456")


def command_tunables(tunables):
    """huge_pages(tunables) and the command's heap thresholds (_COMMAND_HEAP), unless `tunables`
    set them."""
    tunables = huge_pages(tunables)
    for setting in _COMMAND_HEAP:
        if setting.split("=")[0] + "=" not in tunables:
            tunables += ":" + setting
    return tunables


def runs_module(argv, module):
    """Whether the interpreter command line `argv` (sys.orig_argv) runs `module` with -m."""
    k = 1
    while k < len(argv):
        argument = argv[k]
        if argument == "-m":
            return argv[k + 1:k + 2] == [module]
        if argument.startswith("-m"):
            return argument[2:] == module
        if argument in ("-c", "-") or not argument.startswith("-"):
            return False  # (a command, standard input or a script)
        k += 2 if argument in _WITH_VALUE else 1
    return False


def restart_with_huge_pages():
    """This process's command line again, in this process, with GLIBC_TUNABLES asking for huge
    pages and the command's heap thresholds (command_tunables), unless glibc.malloc.hugetlb is in
    them already (then, and if that fails, nothing happens)."""
    tunables = os.environ.get("GLIBC_TUNABLES", "")
    if "glibc.malloc.hugetlb" in tunables or not getattr(sys, "orig_argv", None):
        return
    try:
        os.execve(sys.executable, sys.orig_argv, dict(os.environ, GLIBC_TUNABLES=command_tunables(tunables)))
    except OSError:
        pass  # (then without)


def restart_the_dask_command():
    """restart_with_huge_pages, if this process is `python3 -m toposimp.dask`."""
    if runs_module(getattr(sys, "orig_argv", []), "toposimp.dask"):
        restart_with_huge_pages()
