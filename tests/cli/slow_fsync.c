/* Test-only LD_PRELOAD shim for tests/cli/output_tests.sh: makes fsync(2), which the image
 * writer calls on its complete temporary file just before renaming it into place, create
 * the file named by $CST_TEST_FSYNC_MARK and then sleep $CST_TEST_FSYNC_DELAY_MS ms, so a
 * signal can be sent while the temporary file certainly exists. Nothing in caustic itself
 * knows about it. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <fcntl.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

int fsync(int fd)
{
    const char *mark = getenv("CST_TEST_FSYNC_MARK");
    const char *delay = getenv("CST_TEST_FSYNC_DELAY_MS");
    if (mark) {
        int m = open(mark, O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
        if (m >= 0) close(m);
    }
    if (delay) {
        long ms = strtol(delay, NULL, 10);
        struct timespec ts = {ms / 1000, (ms % 1000) * 1000000L};
        while (nanosleep(&ts, &ts) != 0) {
        }
    }
    int (*real)(int) = (int (*)(int))dlsym(RTLD_NEXT, "fsync");
    return real ? real(fd) : 0;
}
