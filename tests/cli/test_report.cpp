// The stdout capture behind FOLDER/index.html's "What it printed" (cli/report.h).
#include "cli/report.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <unistd.h>

using namespace armsim;

// A command that printed more than one buffer and then returns an error without flushing: stdio
// flushes the captured stream at exit, after the static destructors. Every byte reaches the file and
// the exit status is the command's (the capture's buffer used to be destroyed by then: a double free).
TEST(StdoutCapture, OutputPendingAtExitArrivesWhole) {
    constexpr std::size_t kBytes = 4 * BUFSIZ + 123;   // four full buffers (the copy's capacity then full), then a partial one
    const std::filesystem::path file = std::filesystem::temp_directory_path() / ("armsim_capture_" + std::to_string(getpid()));
    EXPECT_EXIT(
        {
            const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
            if (fd < 0 || ::dup2(fd, STDOUT_FILENO) < 0) std::_Exit(9);
            cli::startStdoutCapture();
            for (std::size_t k = 0; k < kBytes; ++k) std::fputc('a' + int(k % 26), stdout);
            std::exit(2);
        },
        ::testing::ExitedWithCode(2), "");
    std::ifstream in(file, std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::filesystem::remove(file);
    ASSERT_EQ(text.size(), kBytes);
    for (std::size_t k = 0; k < kBytes; ++k)
        if (text[k] != char('a' + int(k % 26))) FAIL() << "byte " << k;
}
