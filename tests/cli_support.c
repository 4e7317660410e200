/* cli_support.c — running the tessera binary from tests; see cli_support.h. */
#include "cli_support.h"

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

pid_t cli_start(const char *errlog, const char *const *args, const char *const *env)
{
    const char *bin = getenv("TS_BINARY");
    if (!bin) fail_msg("TS_BINARY is not set (run through ctest)");
    pid_t pid = fork();
    if (pid == 0) {
        int fd = open(errlog, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        dup2(fd, 2);
        int null = open("/dev/null", O_WRONLY);
        dup2(null, 1);
        unsetenv("JOB_COMPLETION_INDEX");
        unsetenv("SLURM_ARRAY_TASK_ID");
        unsetenv("SLURM_ARRAY_TASK_COUNT");
        unsetenv("SLURM_ARRAY_TASK_MIN");
        for (int i = 0; env && env[i]; i++) putenv((char *)env[i]);
        char *argv[48];
        int n = 0;
        argv[n++] = (char *)bin;
        for (; args[n - 1] && n < 47; n++) argv[n] = (char *)args[n - 1];
        argv[n] = NULL;
        execv(bin, argv);
        _exit(127);
    }
    return pid;
}

int cli_finish(pid_t pid)
{
    int status;
    waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

int cli_run(const char *errlog, const char *const *args, const char *const *env)
{
    return cli_finish(cli_start(errlog, args, env));
}

const char *cli_read_log(const char *errlog)
{
    static char buf[8192];
    FILE *f = fopen(errlog, "r");
    size_t n = f ? fread(buf, 1, sizeof buf - 1, f) : 0;
    if (f) fclose(f);
    buf[n] = '\0';
    return buf;
}

void cli_write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

bool cli_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}
