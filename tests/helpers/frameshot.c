/*
 * frameshot: a test helper, preloaded *before* glray, that makes an unmodified GL program
 * repeatable and takes its picture.
 *
 * - Clock: clock_gettime, gettimeofday and time return a fake time that starts at a fixed
 *   instant (FRAMESHOT_TIME, seconds since 1970, if set) and advances 1/60 s per swap, so animations (glxgears' angle, a hack's motion) depend
 *   on the frame number only. getpid returns a constant, so that seeds built from time and pid
 *   (xscreensaver's ya_rand_init) are the same in every run.
 * - Picture: at swap number FRAMESHOT_FRAME (default 3) of glXSwapBuffers or eglSwapBuffers, the
 *   back buffer of the current viewport is read with glReadPixels and written as a binary PPM to
 *   FRAMESHOT_OUT; that swap goes ahead (so a recorded trace ends that frame too), and the
 *   program exits with status 0 at the next swap.
 *
 * Everything reaches the next library in symbol order (glray when it is loaded, else libGL), so
 * the picture is what the program would have shown, with or without glray.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

typedef unsigned int GLenum;
#define GL_VIEWPORT 0x0BA2
#define GL_RGB 0x1907
#define GL_UNSIGNED_BYTE 0x1401
#define GL_PACK_ALIGNMENT 0x0D05
#define GL_BACK 0x0405

static long frame_no;

/* The fake clock's first instant: FRAMESHOT_TIME (seconds since 1970), else a fixed one. A hack
 * that draws by the time of day (glplanet's sun) shows another picture at another time. */
static long long start_ns(void) {
    static long long start = -1;
    if (start < 0) {
        const char *at = getenv("FRAMESHOT_TIME");
        start = (at ? atoll(at) : 1700000000LL) * 1000000000LL;
    }
    return start;
}

static long long fake_ns(void) { return start_ns() + frame_no * 16666667LL; }

int clock_gettime(clockid_t clk, struct timespec *ts) {
    (void)clk;
    long long ns = fake_ns();
    ts->tv_sec = ns / 1000000000LL;
    ts->tv_nsec = ns % 1000000000LL;
    return 0;
}

int gettimeofday(struct timeval *tv, void *tz) {
    (void)tz;
    long long ns = fake_ns();
    if (tv) {
        tv->tv_sec = ns / 1000000000LL;
        tv->tv_usec = (ns % 1000000000LL) / 1000;
    }
    return 0;
}

time_t time(time_t *t) {
    time_t s = (time_t)(fake_ns() / 1000000000LL);
    if (t) *t = s;
    return s;
}

pid_t getpid(void) { return 4242; }

static void *next(const char *name) {
    void *p = dlsym(RTLD_NEXT, name);
    if (!p) {
        fprintf(stderr, "frameshot: no next %s\n", name);
        _exit(97);
    }
    return p;
}

static int exit_at_next_swap;

static void shoot_if_due(void) {
    if (exit_at_next_swap) exit(0);
    frame_no++;
    const char *want = getenv("FRAMESHOT_FRAME");
    long due = want ? atol(want) : 3;
    if (frame_no != due) return;
    void (*getIntegerv)(GLenum, int *) = (void (*)(GLenum, int *))dlsym(RTLD_DEFAULT, "glGetIntegerv");
    void (*pixelStorei)(GLenum, int) = (void (*)(GLenum, int))dlsym(RTLD_DEFAULT, "glPixelStorei");
    void (*readBuffer)(GLenum) = (void (*)(GLenum))dlsym(RTLD_DEFAULT, "glReadBuffer");
    void (*readPixels)(int, int, int, int, GLenum, GLenum, void *) =
        (void (*)(int, int, int, int, GLenum, GLenum, void *))dlsym(RTLD_DEFAULT, "glReadPixels");
    int vp[4] = {0, 0, 0, 0};
    getIntegerv(GL_VIEWPORT, vp);
    int w = vp[2], h = vp[3];
    if (w <= 0 || h <= 0 || w > 8192 || h > 8192) {
        fprintf(stderr, "frameshot: bad viewport %dx%d\n", w, h);
        _exit(98);
    }
    unsigned char *px = malloc((size_t)w * h * 3);
    pixelStorei(GL_PACK_ALIGNMENT, 1);
    readBuffer(GL_BACK);
    readPixels(vp[0], vp[1], w, h, GL_RGB, GL_UNSIGNED_BYTE, px);
    const char *out = getenv("FRAMESHOT_OUT");
    FILE *f = fopen(out ? out : "frameshot.ppm", "wb");
    if (!f) {
        perror("frameshot: open output");
        _exit(99);
    }
    fprintf(f, "P6\n%d %d\n255\n", w, h);
    for (int y = h - 1; y >= 0; y--) fwrite(px + (size_t)y * w * 3, 1, (size_t)w * 3, f);
    fclose(f);
    fprintf(stderr, "frameshot: frame %ld (%dx%d) written\n", frame_no, w, h);
    exit_at_next_swap = 1;
}

void glXSwapBuffers(void *dpy, unsigned long drawable) {
    static void (*real)(void *, unsigned long);
    if (!real) real = (void (*)(void *, unsigned long))next("glXSwapBuffers");
    shoot_if_due();
    real(dpy, drawable);
}

unsigned int eglSwapBuffers(void *dpy, void *surface) {
    static unsigned int (*real)(void *, void *);
    if (!real) real = (unsigned int (*)(void *, void *))next("eglSwapBuffers");
    shoot_if_due();
    return real(dpy, surface);
}
