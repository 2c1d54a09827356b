// The `toposimp` executable itself: mesh jobs on mesh files run without loading GDAL, every
// other command line is handed to toposimp-gdal (apps/toposimp/main.cpp).
#include "cli/mesh_command.hpp"
#include "cli_fixtures.hpp"

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace toposimp::testing {
namespace {

std::string slurp(const std::filesystem::path& path) {
    std::ifstream in(path);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Runs `binary args` through the shell with the dynamic loader listing every library it loads
// (LD_DEBUG=files, on stderr); returns the exit status, stderr in `err`.
int run_traced(const std::string& binary, const std::string& args, const std::filesystem::path& dir, std::string& err) {
    const std::string command = "LD_DEBUG=files '" + binary + "' " + args + " >'" + (dir / "out.txt").string() + "' 2>'" +
                                (dir / "err.txt").string() + "'";
    const int status = std::system(command.c_str());
    err = slurp(dir / "err.txt");
    return WEXITSTATUS(status);
}

TEST(Launcher, MeshFilesRunWithoutGdal) {
    const auto dir = fresh_dir("launcher");
    const std::string out = (dir / "torus.ply").string();
    std::string err;
    ASSERT_EQ(run_traced(TOPOSIMP_BINARY, "mesh '" + testdata("mesh/torus.off") + "' -o '" + out + "' --keep 20% -q", dir, err), 0) << err;
    EXPECT_TRUE(std::filesystem::exists(out));
    EXPECT_NE(err.find("libgmp"), std::string::npos) << "no loader trace: " << err.substr(0, 2000);
    EXPECT_EQ(err.find("libgdal"), std::string::npos) << "GDAL loaded for a mesh file job";
    // The same output as the whole tool in-process.
    const std::string in_process = (dir / "in_process.ply").string();
    ASSERT_EQ(run_cli({"mesh", testdata("mesh/torus.off"), "-o", in_process, "--keep", "20%", "-q"}).code, 0);
    EXPECT_EQ(slurp(out), slurp(in_process));
}

TEST(Launcher, GisJobsGoToTheWholeTool) {
    const auto dir = fresh_dir("launcher");
    std::string err;
    // An OGR layer out: GDAL is loaded, the layer written.
    const std::string gpkg = (dir / "tin.gpkg").string();
    ASSERT_EQ(run_traced(TOPOSIMP_BINARY, "mesh '" + testdata("mesh/hills.obj") + "' --terrain -o '" + gpkg + "' -q", dir, err), 0) << err;
    EXPECT_NE(err.find("libgdal"), std::string::npos);
    EXPECT_TRUE(std::filesystem::exists(gpkg));
    // --version names GDAL's version; a map job's usage error keeps its message and exit status.
    ASSERT_EQ(run_traced(TOPOSIMP_BINARY, "--version", dir, err), 0);
    EXPECT_NE(slurp(dir / "out.txt").find("(GDAL "), std::string::npos);
    EXPECT_EQ(run_traced(TOPOSIMP_BINARY, "map", dir, err), 2);
    EXPECT_NE(err.find("toposimp: error: input is required"), std::string::npos);
}

TEST(Launcher, MeshCommandWithoutGdalRefusesGisJobs) {
    cli::MeshCommandOptions options;
    options.input = testdata("mesh/hills.obj");
    options.output = (fresh_dir("launcher") / "tin.gpkg").string();
    std::ostringstream out, err;
    cli::Context context{out, err, false};
    EXPECT_EQ(cli::run_mesh(options, context, {}), 2);
    EXPECT_NE(err.str().find("needs GDAL"), std::string::npos) << err.str();
    EXPECT_FALSE(std::filesystem::exists(options.output));
}

// Jobs run with glibc's malloc asking for transparent huge pages, unless the user set that tunable
// (other tunables the user set are kept): map jobs in the whole tool, mesh files of 8 MiB or more
// here (this program started again with it; a small one runs as it is).
TEST(Launcher, JobsGetHugePagesForTheirHeap) {
    const auto dir = fresh_dir("launcher");
    const std::string binary = "'" + std::string(TOPOSIMP_BINARY) + "' ";
    const std::string map = binary + "map '" + testdata("nh_borders.gpkg") + "' --keep 50% -v -o '";
    // A mesh file past 8 MiB: the torus with a comment line of 8 MiB.
    const auto big = dir / "big_torus.off";
    {
        const std::string torus = slurp(testdata("mesh/torus.off"));
        std::ofstream out(big, std::ios::binary);
        out << torus.substr(0, torus.find('\n') + 1) << "# " << std::string(8u << 20, 'x') << "\n" << torus.substr(torus.find('\n') + 1);
    }
    const std::string mesh = binary + "mesh '" + big.string() + "' --keep 50% -v -o '";
    auto run = [&](const std::string& environment, const std::string& job, const std::string& name) {
        const std::string command = environment + " " + job + (dir / name).string() + "' 2>'" + (dir / "err.txt").string() + "'";
        EXPECT_EQ(WEXITSTATUS(std::system(command.c_str())), 0) << command;
        return slurp(dir / "err.txt");
    };
    const std::string asked = "transparent huge pages asked for (glibc.malloc.hugetlb=1";
    int k = 0;
    for (const std::string& job : {map, mesh}) {
        const std::string extension = job == map ? ".gpkg" : ".ply";
        EXPECT_NE(run("env -u GLIBC_TUNABLES", job, std::to_string(k++) + extension).find(asked), std::string::npos) << job;
        EXPECT_NE(run("GLIBC_TUNABLES=glibc.malloc.check=0", job, std::to_string(k++) + extension).find(asked), std::string::npos) << job;
        const std::string refused = run("GLIBC_TUNABLES=glibc.malloc.hugetlb=0", job, std::to_string(k++) + extension);
        EXPECT_EQ(refused.find(asked), std::string::npos) << job;
        EXPECT_NE(refused.find("glibc.malloc.hugetlb is not 1"), std::string::npos) << refused;
    }
    const std::string small = run("env -u GLIBC_TUNABLES", binary + "mesh '" + testdata("mesh/torus.off") + "' --keep 50% -v -o '", "small.ply");
    EXPECT_NE(small.find("glibc.malloc.hugetlb is not 1"), std::string::npos) << small;
}

TEST(Launcher, MissingWholeToolIsAClearError) {
    const auto dir = fresh_dir("launcher");
    const auto alone = dir / "toposimp";
    std::filesystem::copy_file(TOPOSIMP_BINARY, alone);
    std::string err;
    EXPECT_EQ(run_traced(alone.string(), "map in.gpkg -o out.gpkg", dir, err), 2);
    EXPECT_NE(err.find("toposimp: error: cannot run " + (dir / "../libexec/toposimp/toposimp-gdal").string()), std::string::npos)
        << err.substr(err.size() > 2000 ? err.size() - 2000 : 0);
    // A mesh file job does not need it.
    EXPECT_EQ(run_traced(alone.string(), "mesh '" + testdata("mesh/torus.off") + "' -o '" + (dir / "t.obj").string() + "' -q", dir, err), 0);
}

}  // namespace
}  // namespace toposimp::testing
