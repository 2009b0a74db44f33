// The main of every GoogleTest executable: each run gets a private scratch folder.
//
// ctest runs one test per process. The process makes <tmp>/armsim-test-XXXXXX, points TMPDIR at it (so
// std::filesystem::temp_directory_path() and every armsim command a test starts write there), runs its
// tests and removes the folder when they pass. A failed run keeps it and says where, for a look.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

int main(int argc, char** argv) {
    ::testing::InitGoogleTest(&argc, argv);
    const std::string base = std::filesystem::temp_directory_path().string();
    std::vector<char> pattern(base.begin(), base.end());
    const std::string tail = "/armsim-test-XXXXXX";
    pattern.insert(pattern.end(), tail.begin(), tail.end());
    pattern.push_back('\0');
    if (::mkdtemp(pattern.data()) == nullptr) {
        std::perror(("cannot make a scratch folder under " + base).c_str());
        return 2;
    }
    const std::string scratch(pattern.data());
    ::setenv("TMPDIR", scratch.c_str(), 1);
    const int status = RUN_ALL_TESTS();
    if (status == 0) {
        std::error_code ec;
        std::filesystem::remove_all(scratch, ec);
    } else {
        std::fprintf(stderr, "test scratch folder kept: %s\n", scratch.c_str());
    }
    return status;
}
