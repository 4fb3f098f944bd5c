/* notify_listen.c — stands in for systemd's notification socket in tests:
 *   notify_listen SOCKET_PATH [WATCHDOG_USEC] -- COMMAND [ARGS...]
 * binds an AF_UNIX datagram socket at SOCKET_PATH, runs COMMAND with
 * NOTIFY_SOCKET (and WATCHDOG_USEC when given) in its environment, and
 * prints "PID n" and then every notification it receives, one per line
 * (newlines inside a message become spaces), until COMMAND exits. Its
 * exit status is COMMAND's. */
#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

static void drain(int fd)
{
    char buf[4096];
    ssize_t n;
    while ((n = recv(fd, buf, sizeof buf - 1, MSG_DONTWAIT)) > 0) {
        for (ssize_t i = 0; i < n; i++)
            if (buf[i] == '\n')
                buf[i] = ' ';
        buf[n] = '\0';
        printf("%s\n", buf);
        fflush(stdout);
    }
}

int main(int argc, char **argv)
{
    int sep = 0;
    for (int i = 1; i < argc; i++)
        if (strcmp(argv[i], "--") == 0) {
            sep = i;
            break;
        }
    if (sep < 2 || sep + 1 >= argc) {
        fprintf(stderr, "usage: notify_listen SOCKET [WATCHDOG_USEC] -- "
                        "COMMAND [ARGS...]\n");
        return 2;
    }
    struct sockaddr_un sa = {.sun_family = AF_UNIX};
    if (strlen(argv[1]) >= sizeof sa.sun_path) {
        fprintf(stderr, "notify_listen: socket path too long\n");
        return 2;
    }
    strcpy(sa.sun_path, argv[1]);
    unlink(argv[1]);
    int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (fd < 0 || bind(fd, (struct sockaddr *)&sa, sizeof sa) < 0) {
        perror("notify_listen: bind");
        return 2;
    }
    pid_t pid = fork();
    if (pid < 0) {
        perror("notify_listen: fork");
        return 2;
    }
    if (pid == 0) {
        setenv("NOTIFY_SOCKET", argv[1], 1);
        if (sep == 3)
            setenv("WATCHDOG_USEC", argv[2], 1);
        execv(argv[sep + 1], argv + sep + 1);
        perror("notify_listen: exec");
        _exit(127);
    }
    printf("PID %d\n", (int)pid);
    fflush(stdout);
    int status = 0;
    for (;;) {
        struct pollfd p = {fd, POLLIN, 0};
        poll(&p, 1, 100);
        drain(fd);
        pid_t w = waitpid(pid, &status, WNOHANG);
        if (w == pid)
            break;
        if (w < 0 && errno != EINTR)
            break;
    }
    drain(fd);
    unlink(argv[1]);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}
