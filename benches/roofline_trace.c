/*
 * How often each instruction of one call runs, counted by single-stepping it under ptrace:
 * the CPU executes every instruction itself (AVX-512 too, which valgrind cannot decode), so
 * the counts are exact for the instance the program picks. benches/roofline.sh runs it on
 * step_cost and classifies the counted instructions with objdump.
 *
 *   roofline_trace OFFSET N PROGRAM [ARGS...]
 *
 * OFFSET (hex) is the traced function's address in PROGRAM's ELF file (a position-independent
 * executable, as `nm` prints it); N (>= 1) which call of it to count: a breakpoint stops
 * every call, the Nth is single-stepped from its first instruction until it returns, and the
 * program then runs on at full speed. Prints one line per instruction address reached,
 * "OFFSET COUNT" (hex offset in PROGRAM, or "-" and the address for code outside it, e.g. a
 * libc memcpy), on stdout. The function must run on the program's main thread.
 *
 * Build: gcc -O2 -o target/release/roofline_trace benches/roofline_trace.c
 */
#define _GNU_SOURCE
#include <errno.h>
#include <limits.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ptrace.h>
#include <sys/user.h>
#include <sys/wait.h>
#include <unistd.h>

#define SLOTS (1u << 20) /* open-addressed table of instruction addresses */
static uint64_t keys[SLOTS];
static uint64_t counts[SLOTS];

static void count(uint64_t rip)
{
    uint32_t h = (uint32_t)((rip * 0x9E3779B97F4A7C15ull) >> 44) & (SLOTS - 1);
    while (keys[h] != 0 && keys[h] != rip)
        h = (h + 1) & (SLOTS - 1);
    keys[h] = rip;
    counts[h]++;
}

static void die(const char *what)
{
    perror(what);
    exit(1);
}

/* Waits for the child's next stop: 1 at a SIGTRAP, 0 when it ended; any other signal (the
 * traced program sends itself none) ends the trace. */
static int wait_trap(pid_t pid)
{
    int status;
    if (waitpid(pid, &status, 0) < 0)
        die("waitpid");
    if (WIFEXITED(status) || WIFSIGNALED(status))
        return 0;
    if (!WIFSTOPPED(status) || WSTOPSIG(status) != SIGTRAP) {
        fprintf(stderr, "roofline_trace: the program stopped on signal %d\n", WSTOPSIG(status));
        exit(1);
    }
    return 1;
}

/* The load address of PROGRAM's first mapping (file offset 0). */
static uint64_t load_base(pid_t pid, const char *program)
{
    char maps[64], line[PATH_MAX + 128], real[PATH_MAX];
    if (!realpath(program, real))
        die("realpath");
    snprintf(maps, sizeof maps, "/proc/%d/maps", pid);
    FILE *f = fopen(maps, "r");
    if (!f)
        die("maps");
    uint64_t base = 0;
    while (fgets(line, sizeof line, f)) {
        unsigned long start, offset;
        char path[PATH_MAX] = "";
        if (sscanf(line, "%lx-%*x %*s %lx %*s %*s %4095s", &start, &offset, path) >= 2 &&
            offset == 0 && strcmp(path, real) == 0) {
            base = start;
            break;
        }
    }
    fclose(f);
    if (!base) {
        fprintf(stderr, "roofline_trace: %s is not mapped\n", real);
        exit(1);
    }
    return base;
}

int main(int argc, char **argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: roofline_trace OFFSET N PROGRAM [ARGS...]\n");
        return 2;
    }
    uint64_t offset = strtoull(argv[1], NULL, 16);
    long wanted = strtol(argv[2], NULL, 10);
    pid_t pid = fork();
    if (pid == 0) {
        ptrace(PTRACE_TRACEME, 0, NULL, NULL);
        execv(argv[3], argv + 3);
        die("execv");
    }
    if (!wait_trap(pid)) /* stopped at exec */
        return 1;
    uint64_t base = load_base(pid, argv[3]);
    uint64_t entry = base + offset;
    errno = 0;
    long word = ptrace(PTRACE_PEEKTEXT, pid, (void *)entry, NULL);
    if (errno)
        die("peek");
    long trap = (word & ~0xffL) | 0xcc;
    if (ptrace(PTRACE_POKETEXT, pid, (void *)entry, (void *)trap) < 0)
        die("poke");
    struct user_regs_struct r;
    for (long call = 1;; call++) {
        ptrace(PTRACE_CONT, pid, NULL, NULL);
        if (!wait_trap(pid)) {
            fprintf(stderr, "roofline_trace: the program ended after %ld calls\n", call - 1);
            return 1;
        }
        ptrace(PTRACE_GETREGS, pid, NULL, &r);
        if (r.rip != entry + 1) {
            fprintf(stderr, "roofline_trace: a trap outside the breakpoint\n");
            return 1;
        }
        /* Back to the original instruction, the breakpoint's byte undone. */
        r.rip = entry;
        ptrace(PTRACE_SETREGS, pid, NULL, &r);
        ptrace(PTRACE_POKETEXT, pid, (void *)entry, (void *)word);
        if (call < wanted) {
            ptrace(PTRACE_SINGLESTEP, pid, NULL, NULL);
            wait_trap(pid);
            ptrace(PTRACE_POKETEXT, pid, (void *)entry, (void *)trap);
            continue;
        }
        /* The Nth call: step until the return address is reached with the frame popped. */
        uint64_t sp = r.rsp;
        errno = 0;
        uint64_t ret = (uint64_t)ptrace(PTRACE_PEEKDATA, pid, (void *)sp, NULL);
        if (errno)
            die("peek return address");
        uint64_t steps = 0;
        while (!(r.rip == ret && r.rsp > sp)) {
            count(r.rip);
            steps++;
            ptrace(PTRACE_SINGLESTEP, pid, NULL, NULL);
            if (!wait_trap(pid)) {
                fprintf(stderr, "roofline_trace: the program ended inside the call\n");
                return 1;
            }
            ptrace(PTRACE_GETREGS, pid, NULL, &r);
        }
        fprintf(stderr, "roofline_trace: call %ld, %llu instructions\n", call,
                (unsigned long long)steps);
        break;
    }
    /* Let the program finish, its output discarded by the caller. */
    ptrace(PTRACE_DETACH, pid, NULL, NULL);
    waitpid(pid, NULL, 0);
    for (uint32_t h = 0; h < SLOTS; h++) {
        if (!keys[h])
            continue;
        if (keys[h] >= base && keys[h] - base < (1ull << 32))
            printf("%llx %llu\n", (unsigned long long)(keys[h] - base),
                   (unsigned long long)counts[h]);
        else
            printf("- %llx %llu\n", (unsigned long long)keys[h], (unsigned long long)counts[h]);
    }
    return 0;
}
