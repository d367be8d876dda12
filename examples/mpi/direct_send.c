/* direct_send: a second, independent sort-last MPI host for glray's tests of image-parallel
 * tracing, written apart from icet_like.c and unlike it wherever a host can differ:
 *   - a GLX window per rank (under an X server: Xvfb in the tests), not OSMesa;
 *   - its objects as a buffer object drawn with glDrawElements (tori), client arrays drawn with
 *     glDrawArrays (cones), and display lists of immediate-mode strips (spheres), two lights and
 *     glColorMaterial; object k drawn by rank k % size; the ground by the last rank;
 *   - the camera, not the scene, moves: it circles the scene, a frame a step;
 *   - every rank clears to (0, 0, 0, 0), reads colour (GL_RGBA bytes) then depth (GL_FLOAT),
 *     and the ranks composite by IceT's direct-send: the window cut into one strip of rows per
 *     rank, each rank's strips sent to their owners (MPI_Alltoall), each owner keeping the
 *     nearest fragment (ties to the lower rank), the strips gathered on rank 0;
 *   - rank 0 then does what ParaView does after IceT: clears its window to the background,
 *     pastes the composite over it (glDrawPixels), and swaps; the other
 *     ranks swap their windows too.
 *
 *   mpirun -np N direct_send OUT.ppm [FRAMES [WIDTH HEIGHT]]
 *
 * DIRECT_SEND_STEP=DEGREES: how far the camera moves a frame (default 3; 0: a still view, whose
 * frames a ray tracer may refine).
 *
 * Rank 0 writes the composite of the last frame as a binary PPM (its own, not glray's image
 * code), and each frame's time on standard output. Built with: mpicc direct_send.c -o direct_send -lGL -lX11 -lm (scripts/lib/build.sh). */
#include <GL/gl.h>
#include <GL/glx.h>
#include <X11/Xlib.h>
#include <math.h>
#include <mpi.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef void (*GenBuffers)(GLsizei, GLuint *);
typedef void (*BindBuffer)(GLenum, GLuint);
typedef void (*BufferData)(GLenum, ptrdiff_t, const void *, GLenum);

static void fail(const char *why) {
  fprintf(stderr, "direct_send: %s\n", why);
  MPI_Abort(MPI_COMM_WORLD, 1);
}

#define OBJECTS 7
#define RINGS 24
#define SIDES 16

/* A torus of radii r (tube) and R (ring) as an indexed mesh in two buffer objects. */
static GLuint torus_buffers[2];
static int torus_indices;

static void make_torus(GenBuffers gen, BindBuffer bind, BufferData data) {
  static float v[RINGS * SIDES][6];
  static GLuint idx[RINGS * SIDES * 6];
  const float R = 0.55f, r = 0.2f;
  for (int i = 0; i < RINGS; i++) {
    for (int j = 0; j < SIDES; j++) {
      float a = 2.0f * (float)M_PI * i / RINGS, b = 2.0f * (float)M_PI * j / SIDES;
      float *p = v[i * SIDES + j];
      p[3] = cosf(a) * cosf(b), p[4] = sinf(a) * cosf(b), p[5] = sinf(b);
      p[0] = cosf(a) * (R + r * cosf(b)), p[1] = sinf(a) * (R + r * cosf(b)), p[2] = r * sinf(b);
    }
  }
  int n = 0;
  for (int i = 0; i < RINGS; i++) {
    for (int j = 0; j < SIDES; j++) {
      GLuint a = i * SIDES + j, b = ((i + 1) % RINGS) * SIDES + j, c = ((i + 1) % RINGS) * SIDES + (j + 1) % SIDES,
             d = i * SIDES + (j + 1) % SIDES;
      GLuint q[6] = {a, b, c, a, c, d};
      memcpy(idx + n, q, sizeof q);
      n += 6;
    }
  }
  torus_indices = n;
  gen(2, torus_buffers);
  bind(GL_ARRAY_BUFFER, torus_buffers[0]);
  data(GL_ARRAY_BUFFER, sizeof v, v, GL_STATIC_DRAW);
  bind(GL_ELEMENT_ARRAY_BUFFER, torus_buffers[1]);
  data(GL_ELEMENT_ARRAY_BUFFER, sizeof idx, idx, GL_STATIC_DRAW);
  bind(GL_ARRAY_BUFFER, 0);
  bind(GL_ELEMENT_ARRAY_BUFFER, 0);
}

static void draw_torus(BindBuffer bind) {
  bind(GL_ARRAY_BUFFER, torus_buffers[0]);
  bind(GL_ELEMENT_ARRAY_BUFFER, torus_buffers[1]);
  glEnableClientState(GL_VERTEX_ARRAY);
  glEnableClientState(GL_NORMAL_ARRAY);
  glVertexPointer(3, GL_FLOAT, 6 * sizeof(float), (const void *)0);
  glNormalPointer(GL_FLOAT, 6 * sizeof(float), (const void *)(3 * sizeof(float)));
  glDrawElements(GL_TRIANGLES, torus_indices, GL_UNSIGNED_INT, (const void *)0);
  glDisableClientState(GL_NORMAL_ARRAY);
  glDisableClientState(GL_VERTEX_ARRAY);
  bind(GL_ARRAY_BUFFER, 0);
  bind(GL_ELEMENT_ARRAY_BUFFER, 0);
}

/* A cone (apex up) from client arrays: a fan for its side, normals per vertex. */
static void draw_cone(void) {
  float v[(SIDES + 2) * 3], n[(SIDES + 2) * 3];
  v[0] = 0, v[1] = 0.8f, v[2] = 0, n[0] = 0, n[1] = 1, n[2] = 0;
  for (int j = 0; j <= SIDES; j++) {
    float a = 2.0f * (float)M_PI * j / SIDES;
    float *p = v + 3 * (j + 1), *q = n + 3 * (j + 1);
    p[0] = 0.4f * cosf(a), p[1] = -0.3f, p[2] = -0.4f * sinf(a);
    q[0] = 0.94f * cosf(a), q[1] = 0.34f, q[2] = -0.94f * sinf(a);
  }
  glEnableClientState(GL_VERTEX_ARRAY);
  glEnableClientState(GL_NORMAL_ARRAY);
  glVertexPointer(3, GL_FLOAT, 0, v);
  glNormalPointer(GL_FLOAT, 0, n);
  glDrawArrays(GL_TRIANGLE_FAN, 0, SIDES + 2);
  glDisableClientState(GL_NORMAL_ARRAY);
  glDisableClientState(GL_VERTEX_ARRAY);
}

/* A sphere of radius 0.45 as a display list of quad strips given vertex by vertex. */
static void sphere_list(GLuint list) {
  glNewList(list, GL_COMPILE);
  for (int i = 0; i < 12; i++) {
    float a0 = (float)M_PI * (i / 12.0f - 0.5f), a1 = (float)M_PI * ((i + 1) / 12.0f - 0.5f);
    glBegin(GL_QUAD_STRIP);
    for (int j = 0; j <= 20; j++) {
      float b = 2.0f * (float)M_PI * j / 20;
      for (int k = 0; k < 2; k++) {
        float a = k ? a0 : a1;
        float x = cosf(a) * cosf(b), y = sinf(a), z = cosf(a) * sinf(b);
        glNormal3f(x, y, z);
        glVertex3f(0.45f * x, 0.45f * y, 0.45f * z);
      }
    }
    glEnd();
  }
  glEndList();
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  int rank, size;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (argc < 2) fail("usage: direct_send OUT.ppm [FRAMES [WIDTH HEIGHT]]");
  int frames = argc > 2 ? atoi(argv[2]) : 3;
  int w = argc > 4 ? atoi(argv[3]) : 320, h = argc > 4 ? atoi(argv[4]) : 240;
  if (frames < 1 || w < size || h < size) fail("bad frames or size");
  float step = getenv("DIRECT_SEND_STEP") ? (float)atof(getenv("DIRECT_SEND_STEP")) : 3.0f;

  Display *dpy = XOpenDisplay(NULL);
  if (!dpy) fail("no X display (DISPLAY)");
  int attrs[] = {GLX_RGBA, GLX_DOUBLEBUFFER, GLX_RED_SIZE, 8, GLX_GREEN_SIZE, 8, GLX_BLUE_SIZE, 8,
                 GLX_ALPHA_SIZE, 8, GLX_DEPTH_SIZE, 24, None};
  XVisualInfo *vi = glXChooseVisual(dpy, DefaultScreen(dpy), attrs);
  if (!vi) fail("no visual");
  XSetWindowAttributes swa = {0};
  swa.colormap = XCreateColormap(dpy, RootWindow(dpy, vi->screen), vi->visual, AllocNone);
  Window win = XCreateWindow(dpy, RootWindow(dpy, vi->screen), 0, 0, w, h, 0, vi->depth, InputOutput, vi->visual,
                             CWColormap, &swa);
  XMapWindow(dpy, win);
  XSync(dpy, False);
  GLXContext ctx = glXCreateContext(dpy, vi, NULL, True);
  if (!ctx || !glXMakeCurrent(dpy, win, ctx)) fail("no GLX context");
  GenBuffers gen = (GenBuffers)glXGetProcAddressARB((const GLubyte *)"glGenBuffers");
  BindBuffer bind = (BindBuffer)glXGetProcAddressARB((const GLubyte *)"glBindBuffer");
  BufferData data = (BufferData)glXGetProcAddressARB((const GLubyte *)"glBufferData");
  if (!gen || !bind || !data) fail("no buffer objects");

  make_torus(gen, bind, data);
  GLuint sphere = glGenLists(1);
  sphere_list(sphere);

  size_t n = (size_t)w * h;
  uint8_t *color = malloc(4 * n), *strips = malloc(4 * n), *mine = malloc(4 * n);
  float *depth = malloc(4 * n), *sdepth = malloc(4 * n), *mdepth = malloc(4 * n);
  uint8_t *final = malloc(4 * n);
  /* Strip k: rows [k h / size, (k + 1) h / size). */
  int *counts = malloc(size * sizeof(int)), *offsets = malloc(size * sizeof(int));
  for (int k = 0; k < size; k++) {
    int y0 = k * h / size, y1 = (k + 1) * h / size;
    offsets[k] = y0 * w, counts[k] = (y1 - y0) * w;
  }
  if (!color || !strips || !mine || !depth || !sdepth || !mdepth || !final) fail("out of memory");
  const float place[OBJECTS][3] = {{-1.3f, 0.45f, 0.2f}, {0.0f, 0.55f, -0.6f}, {1.3f, 0.3f, 0.3f},
                                   {-0.5f, 0.3f, 1.1f}, {0.7f, 0.45f, 1.2f}, {0.2f, 1.3f, 0.4f},
                                   {-1.0f, 1.2f, -0.9f}};
  const float tint[OBJECTS][3] = {{0.9f, 0.3f, 0.2f}, {0.2f, 0.7f, 0.3f}, {0.3f, 0.4f, 0.9f}, {0.9f, 0.8f, 0.2f},
                                  {0.7f, 0.3f, 0.8f}, {0.9f, 0.9f, 0.9f}, {0.3f, 0.8f, 0.8f}};

  for (int frame = 0; frame < frames; frame++) {
    double start = MPI_Wtime();
    glViewport(0, 0, w, h);
    glClearColor(0, 0, 0, 0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glEnable(GL_LIGHTING);
    glEnable(GL_LIGHT0);
    glEnable(GL_LIGHT1);
    glEnable(GL_NORMALIZE);
    glEnable(GL_COLOR_MATERIAL);
    glColorMaterial(GL_FRONT, GL_AMBIENT_AND_DIFFUSE);
    glMatrixMode(GL_PROJECTION);
    glLoadIdentity();
    float aspect = (float)w / h;
    glFrustum(-0.09 * aspect, 0.09 * aspect, -0.09, 0.09, 0.2, 40.0);
    glMatrixMode(GL_MODELVIEW);
    glLoadIdentity();
    /* Lights fixed to the eye: one overhead-left, one weak from the right. */
    const float l0[4] = {-0.4f, 1.0f, 0.6f, 0.0f}, l1[4] = {1.0f, 0.2f, 0.3f, 0.0f};
    const float d1[4] = {0.35f, 0.35f, 0.4f, 1.0f};
    glLightfv(GL_LIGHT0, GL_POSITION, l0);
    glLightfv(GL_LIGHT1, GL_POSITION, l1);
    glLightfv(GL_LIGHT1, GL_DIFFUSE, d1);
    /* The camera circles the scene, `step` degrees a frame, looking slightly down. */
    glTranslatef(0.0f, -0.4f, -6.0f);
    glRotatef(18.0f, 1, 0, 0);
    glRotatef(25.0f + step * frame, 0, 1, 0);
    for (int k = 0; k < OBJECTS; k++) {
      if (k % size != rank) continue;
      glPushMatrix();
      glTranslatef(place[k][0], place[k][1], place[k][2]);
      glColor3fv(tint[k]);
      switch (k % 3) {
        case 0:
          glRotatef(70.0f, 1, 0, 0);
          draw_torus(bind);
          break;
        case 1:
          draw_cone();
          break;
        default:
          glCallList(sphere);
      }
      glPopMatrix();
    }
    if (rank == size - 1) {
      glColor3f(0.75f, 0.72f, 0.68f);
      glNormal3f(0, 1, 0);
      glBegin(GL_QUADS);
      glVertex3f(-4, 0, -4);
      glVertex3f(-4, 0, 4);
      glVertex3f(4, 0, 4);
      glVertex3f(4, 0, -4);
      glEnd();
    }
    glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, color);
    glReadPixels(0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, depth);

    /* Direct send: strip k of every rank to rank k; rank k receives its strip from every rank,
     * in rank order. */
    int own = counts[rank];
    int *sc = malloc(size * sizeof(int)), *sd = malloc(size * sizeof(int));
    int *rc = malloc(size * sizeof(int)), *rd = malloc(size * sizeof(int));
    if (!sc || !sd || !rc || !rd) fail("out of memory");
    for (int k = 0; k < size; k++) sc[k] = 4 * counts[k], sd[k] = 4 * offsets[k], rc[k] = 4 * own, rd[k] = 4 * k * own;
    MPI_Alltoallv(color, sc, sd, MPI_BYTE, strips, rc, rd, MPI_BYTE, MPI_COMM_WORLD);
    for (int k = 0; k < size; k++) sc[k] = counts[k], sd[k] = offsets[k], rc[k] = own, rd[k] = k * own;
    MPI_Alltoallv(depth, sc, sd, MPI_FLOAT, sdepth, rc, rd, MPI_FLOAT, MPI_COMM_WORLD);
    /* The nearest fragment of each pixel of the strip (ties: the lower rank's). */
    for (int p = 0; p < own; p++) {
      int best = 0;
      for (int j = 1; j < size; j++)
        if (sdepth[j * own + p] < sdepth[best * own + p]) best = j;
      memcpy(mine + 4 * p, strips + 4 * ((size_t)best * own + p), 4);
      mdepth[p] = sdepth[best * own + p];
    }
    for (int k = 0; k < size; k++) sc[k] = 4 * counts[k], sd[k] = 4 * offsets[k];
    MPI_Gatherv(mine, 4 * own, MPI_BYTE, final, sc, sd, MPI_BYTE, 0, MPI_COMM_WORLD);
    free(sc), free(sd), free(rc), free(rd);

    if (rank == 0) {
      /* The composite is premultiplied over (0, 0, 0, 0): put it over the background. */
      const float bg[3] = {0.15f, 0.18f, 0.24f};
      for (size_t p = 0; p < n; p++) {
        float a = final[4 * p + 3] / 255.0f;
        for (int c = 0; c < 3; c++) {
          float v = final[4 * p + c] + (1.0f - a) * 255.0f * bg[c];
          final[4 * p + c] = (uint8_t)(v > 255.0f ? 255.0f : v + 0.5f);
        }
        final[4 * p + 3] = 255;
      }
      /* Shown as ParaView shows IceT's image: the window cleared to the background, the
       * composite pasted over it, swapped. */
      glClearColor(bg[0], bg[1], bg[2], 1.0f);
      glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
      glDisable(GL_DEPTH_TEST);
      glDisable(GL_LIGHTING);
      glMatrixMode(GL_PROJECTION);
      glLoadIdentity();
      glMatrixMode(GL_MODELVIEW);
      glLoadIdentity();
      glRasterPos2f(-1.0f, -1.0f);
      glDrawPixels(w, h, GL_RGBA, GL_UNSIGNED_BYTE, final);
      if (frame + 1 == frames) {
        FILE *f = fopen(argv[1], "wb");
        if (!f) fail("cannot write the picture");
        fprintf(f, "P6\n%d %d\n255\n", w, h);
        for (int y = h - 1; y >= 0; y--)
          for (int x = 0; x < w; x++) fwrite(final + 4 * ((size_t)y * w + x), 1, 3, f);
        fclose(f);
      }
    }
    glXSwapBuffers(dpy, win);
    /* A frame's time, drawing to swap, as the host sees it (scripts/bench-mpi). */
    if (rank == 0) printf("direct_send: frame %d: %.4f s\n", frame, MPI_Wtime() - start);
  }
  glXMakeCurrent(dpy, None, NULL);
  glXDestroyContext(dpy, ctx);
  XDestroyWindow(dpy, win);
  XCloseDisplay(dpy);
  MPI_Finalize();
  return 0;
}
