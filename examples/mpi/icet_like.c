/* icet_like: a data-parallel MPI program in the style of ParaView with IceT, for glray's tests,
 * benchmarks and demo. Each rank draws only its own objects (display lists; rank 0 also the
 * ground), every rank reads back colour then depth with glReadPixels as IceT does, and rank 0
 * composites by depth (sort-last; ties to the lower rank) and writes a PNG. Rendered by Mesa,
 * the picture is the same for any number of ranks; under glray with `distribute=replicated`
 * every rank traces tiles of the whole scene, so shadows, ambient occlusion and reflections
 * see every rank's objects.
 *
 *   mpirun -np N icet_like OUT.png [FRAMES [WIDTH HEIGHT [OBJECTS [MESH]]]]
 *
 * With MESH (the anchors' ISOMESH1 file, `glray bench --save-mesh`), the ranks split the mesh's
 * triangles instead of boxes, seen by the anchors' camera and light (scripts/bench-mpi); rank 0
 * prints each frame's time.
 *
 * ICET_LIKE_ORBIT=DEGREES[:FIRST] turns the scene (not the light) about its vertical axis by DEGREES
 * a frame, frame f at (FIRST + f) x DEGREES: a moving scene, for glray's quality benchmark
 * (scripts/bench-quality), whose frame FIRST + n a one-frame run with FIRST + n shows alone.
 *
 * ICET_LIKE_OVERLAY=1 makes rank 0 also draw what visualization programs draw over a 3D scene: a
 * grid of unlit lines on the ground and a translucent panel over the left of the window (an
 * orthographic overlay, blended), for glray's tests of AO under lines and overlays.
 *
 * ICET_LIKE_FRAME_MS=MS waits that long before each frame: a program that runs long enough for a
 * test to steer it from glray's live control panel.
 *
 * ICET_LIKE_STALL=RANK:FRAME makes that rank stop itself (SIGSTOP) as that frame begins: a rank
 * that stops answering, for glray's tests of its time limits.
 *
 * ICET_LIKE_PIECES=N (with MESH) draws each rank's share of the mesh as N display lists of
 * consecutive triangles: one process drawing the mesh in as many pieces as N ranks draw it
 * (scripts/bench-mpi: what tracing a scene in pieces costs apart from MPI).
 *
 * Built with: mpicc icet_like.c -o icet_like -lOSMesa -lz -lm (scripts/lib/build.sh). */
#include <GL/gl.h>
#include <GL/osmesa.h>
#include <mpi.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <math.h>
#include <zlib.h>

static void die(const char *what) {
  fprintf(stderr, "icet_like: %s\n", what);
  MPI_Abort(MPI_COMM_WORLD, 1);
}

/* A unit cube, as triangles with a normal per face. */
static void cube_list(GLuint list) {
  static const float n[6][3] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
  static const float c[6][4][3] = {
      {{-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}},     {{1, -1, -1}, {-1, -1, -1}, {-1, 1, -1}, {1, 1, -1}},
      {{1, -1, 1}, {1, -1, -1}, {1, 1, -1}, {1, 1, 1}},     {{-1, -1, -1}, {-1, -1, 1}, {-1, 1, 1}, {-1, 1, -1}},
      {{-1, 1, 1}, {1, 1, 1}, {1, 1, -1}, {-1, 1, -1}},     {{-1, -1, -1}, {1, -1, -1}, {1, -1, 1}, {-1, -1, 1}}};
  static const int tri[6] = {0, 1, 2, 0, 2, 3};
  glNewList(list, GL_COMPILE);
  glBegin(GL_TRIANGLES);
  for (int f = 0; f < 6; f++) {
    glNormal3fv(n[f]);
    for (int k = 0; k < 6; k++) glVertex3fv(c[f][tri[k]]);
  }
  glEnd();
  glEndList();
}

static void put32(unsigned char *p, uint32_t v) {
  p[0] = v >> 24, p[1] = v >> 16, p[2] = v >> 8, p[3] = v;
}

static void chunk(FILE *f, const char *type, const unsigned char *data, uint32_t len) {
  unsigned char head[8];
  put32(head, len);
  memcpy(head + 4, type, 4);
  fwrite(head, 1, 8, f);
  if (len) fwrite(data, 1, len, f);
  uLong crc = crc32(0, (const Bytef *)type, 4);
  if (len) crc = crc32(crc, data, len);
  unsigned char tail[4];
  put32(tail, (uint32_t)crc);
  fwrite(tail, 1, 4, f);
}

/* RGBA rows bottom-up (as GL reads them) to an RGB PNG, top row first. */
static void write_png(const char *path, const unsigned char *rgba, int w, int h) {
  size_t raw_len = (size_t)h * (1 + 3 * (size_t)w);
  unsigned char *raw = malloc(raw_len);
  for (int y = 0; y < h; y++) {
    unsigned char *row = raw + (size_t)y * (1 + 3 * (size_t)w);
    const unsigned char *src = rgba + (size_t)(h - 1 - y) * 4 * w;
    row[0] = 0;
    for (int x = 0; x < w; x++) memcpy(row + 1 + 3 * x, src + 4 * x, 3);
  }
  uLongf z_len = compressBound(raw_len);
  unsigned char *z = malloc(z_len);
  if (compress2(z, &z_len, raw, raw_len, 6) != Z_OK) die("zlib failed");
  FILE *f = fopen(path, "wb");
  if (!f) die("cannot write the PNG");
  fwrite("\x89PNG\r\n\x1a\n", 1, 8, f);
  unsigned char ihdr[13];
  put32(ihdr, w), put32(ihdr + 4, h);
  ihdr[8] = 8, ihdr[9] = 2, ihdr[10] = 0, ihdr[11] = 0, ihdr[12] = 0;
  chunk(f, "IHDR", ihdr, 13);
  chunk(f, "IDAT", z, (uint32_t)z_len);
  chunk(f, "IEND", NULL, 0);
  fclose(f);
  free(raw), free(z);
}

/* The anchors' isosurface (common.h's format and camera). */
typedef struct {
  uint32_t nv, nt;
  float *pos, *nrm;
  uint32_t *idx;
} Mesh;

static Mesh read_mesh(const char *path) {
  Mesh m = {0};
  FILE *f = fopen(path, "rb");
  char magic[8];
  if (!f || fread(magic, 1, 8, f) != 8 || memcmp(magic, "ISOMESH1", 8) || fread(&m.nv, 4, 1, f) != 1 ||
      fread(&m.nt, 4, 1, f) != 1)
    die("cannot read the mesh (ISOMESH1)");
  m.pos = malloc(12 * (size_t)m.nv), m.nrm = malloc(12 * (size_t)m.nv), m.idx = malloc(12 * (size_t)m.nt);
  if (fread(m.pos, 12, m.nv, f) != m.nv || fread(m.nrm, 12, m.nv, f) != m.nv || fread(m.idx, 12, m.nt, f) != m.nt)
    die("the mesh is cut short");
  fclose(f);
  return m;
}

/* Triangles [first, last) of the mesh in display list `list`. */
static void mesh_list(GLuint list, const Mesh *m, size_t first, size_t last) {
  glNewList(list, GL_COMPILE);
  glBegin(GL_TRIANGLES);
  for (size_t t = first; t < last; t++)
    for (int k = 0; k < 3; k++) {
      uint32_t v = m->idx[3 * t + k];
      glNormal3fv(m->nrm + 3 * v);
      glVertex3fv(m->pos + 3 * v);
    }
  glEnd();
  glEndList();
}

/* gluLookAt from the anchors' eye to the origin, y up. */
static void look_at(const float eye[3]) {
  float f[3] = {-eye[0], -eye[1], -eye[2]}, l = sqrtf(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  for (int i = 0; i < 3; i++) f[i] /= l;
  float s[3] = {-f[2], 0.0f, f[0]}; /* f x (0,1,0) */
  l = sqrtf(s[0] * s[0] + s[2] * s[2]);
  s[0] /= l, s[2] /= l;
  float u[3] = {s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2], s[0] * f[1] - s[1] * f[0]};
  float m[16] = {s[0], u[0], -f[0], 0, s[1], u[1], -f[1], 0, s[2], u[2], -f[2], 0, 0, 0, 0, 1};
  glMultMatrixf(m);
  glTranslatef(-eye[0], -eye[1], -eye[2]);
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  int rank, size;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (argc < 2) die("usage: icet_like OUT.png [FRAMES [WIDTH HEIGHT [OBJECTS]]]");
  int frames = argc > 2 ? atoi(argv[2]) : 2;
  int w = argc > 4 ? atoi(argv[3]) : 256, h = argc > 4 ? atoi(argv[4]) : 192;
  int objects = argc > 5 ? atoi(argv[5]) : 8;
  const char *mesh_path = argc > 6 ? argv[6] : NULL;
  if (frames < 1 || w < 1 || h < 1 || objects < 1) die("bad arguments");
  float orbit = 0.0f;
  int orbit_first = 0;
  if (getenv("ICET_LIKE_ORBIT")) sscanf(getenv("ICET_LIKE_ORBIT"), "%f:%d", &orbit, &orbit_first);
  int overlay = getenv("ICET_LIKE_OVERLAY") && atoi(getenv("ICET_LIKE_OVERLAY"));
  int frame_ms = getenv("ICET_LIKE_FRAME_MS") ? atoi(getenv("ICET_LIKE_FRAME_MS")) : 0;
  int stall_rank = -1, stall_frame = -1;
  if (getenv("ICET_LIKE_STALL")) sscanf(getenv("ICET_LIKE_STALL"), "%d:%d", &stall_rank, &stall_frame);
  /* For tests that signal a rank from outside. */
  fprintf(stderr, "icet_like: rank %d of %d is pid %ld\n", rank, size, (long)getpid());

  unsigned char *buffer = malloc((size_t)w * h * 4);
  OSMesaContext ctx = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, NULL);
  if (!ctx || !OSMesaMakeCurrent(ctx, buffer, GL_UNSIGNED_BYTE, w, h)) die("no OSMesa context");

  glViewport(0, 0, w, h);
  glMatrixMode(GL_PROJECTION);
  glLoadIdentity();
  double aspect = (double)w / h;
  if (mesh_path) {
    /* the anchors' gluPerspective(40, aspect, 0.5, 10); ICET_LIKE_ZOOM=4 narrows it to a quarter
       (a zoomed-in view, as paging's cache study takes one) */
    double zoom = getenv("ICET_LIKE_ZOOM") ? atof(getenv("ICET_LIKE_ZOOM")) : 1.0;
    if (!(zoom > 0.0)) die("bad ICET_LIKE_ZOOM");
    double top = 0.5 * tan(40.0 * M_PI / 360.0) / zoom;
    glFrustum(-top * aspect, top * aspect, -top, top, 0.5, 10.0);
  } else {
    glFrustum(-0.5 * aspect, 0.5 * aspect, -0.5, 0.5, 1.0, 40.0);
  }
  glMatrixMode(GL_MODELVIEW);
  glEnable(GL_DEPTH_TEST);
  glEnable(GL_LIGHTING);
  glEnable(GL_LIGHT0);
  glEnable(GL_COLOR_MATERIAL);
  glEnable(GL_NORMALIZE);
  cube_list(1);
  int pieces = getenv("ICET_LIKE_PIECES") ? atoi(getenv("ICET_LIKE_PIECES")) : 1;
  if (pieces < 1) die("bad ICET_LIKE_PIECES");
  if (mesh_path) {
    Mesh m = read_mesh(mesh_path);
    size_t from = (size_t)rank * m.nt / size, to = (size_t)(rank + 1) * m.nt / size;
    for (int k = 0; k < pieces; k++)
      mesh_list(2 + k, &m, from + (to - from) * k / pieces, from + (to - from) * (k + 1) / pieces);
    free(m.pos), free(m.nrm), free(m.idx);
  }

  /* This rank's objects: a block of them in rank order, as a data-parallel reader splits. */
  int first = rank * objects / size, last = (rank + 1) * objects / size;
  size_t n = (size_t)w * h;
  unsigned char *color = malloc(4 * n), *colors = rank == 0 ? malloc(4 * n * size) : NULL;
  float *depth = malloc(sizeof(float) * n), *depths = rank == 0 ? malloc(sizeof(float) * n * size) : NULL;
  unsigned char *image = rank == 0 ? malloc(4 * n) : NULL;

  for (int frame = 0; frame < frames; frame++) {
    if (frame_ms > 0) usleep(1000 * frame_ms);
    MPI_Barrier(MPI_COMM_WORLD);
    if (rank == stall_rank && frame == stall_frame) raise(SIGSTOP);
    double start = MPI_Wtime();
    glClearColor(0.25f, 0.3f, 0.38f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glLoadIdentity();
    if (mesh_path) {
      static const float eye[3] = {1.45f, 1.05f, 1.95f};
      const GLfloat dir[4] = {-0.5f, 0.8f, 0.35f, 0.0f};
      look_at(eye);
      glLightfv(GL_LIGHT0, GL_POSITION, dir);
      glRotatef(orbit * (orbit_first + frame), 0.0f, 1.0f, 0.0f);
      glColor3f(0.8f, 0.7f, 0.5f);
      glNormal3f(0.0f, 0.0f, 1.0f);
      for (int k = 0; k < pieces; k++) glCallList(2 + k);
    } else {
      glTranslatef(0.0f, -1.2f, -11.0f);
      glRotatef(28.0f, 1.0f, 0.0f, 0.0f);
      glRotatef(-20.0f, 0.0f, 1.0f, 0.0f);
      const GLfloat light[4] = {-3.0f, 8.0f, 5.0f, 1.0f};
      glLightfv(GL_LIGHT0, GL_POSITION, light);
      glRotatef(orbit * (orbit_first + frame), 0.0f, 1.0f, 0.0f);
      if (rank == 0) {
        glColor3f(0.85f, 0.85f, 0.8f);
        glBegin(GL_QUADS);
        glNormal3f(0.0f, 1.0f, 0.0f);
        glVertex3f(-8.0f, -1.0f, 6.0f);
        glVertex3f(8.0f, -1.0f, 6.0f);
        glVertex3f(8.0f, -1.0f, -8.0f);
        glVertex3f(-8.0f, -1.0f, -8.0f);
        glEnd();
        if (overlay) {
          /* A grid on the ground, unlit, as axes and outlines are drawn. */
          glDisable(GL_LIGHTING);
          glColor3f(0.35f, 0.35f, 0.3f);
          glBegin(GL_LINES);
          for (int g = -8; g <= 6; g++) {
            glVertex3f(-8.0f, -0.99f, (float)g);
            glVertex3f(8.0f, -0.99f, (float)g);
          }
          for (int g = -8; g <= 8; g++) {
            glVertex3f((float)g, -0.99f, 6.0f);
            glVertex3f((float)g, -0.99f, -8.0f);
          }
          glEnd();
          glEnable(GL_LIGHTING);
        }
      }
      for (int k = first; k < last; k++) {
        float t = objects > 1 ? (float)k / (objects - 1) : 0.5f;
        glPushMatrix();
        glTranslatef(-5.0f + 10.0f * t, -0.2f + 0.6f * (k % 3), -2.0f + 2.5f * (k % 2));
        glRotatef(35.0f * k, 0.0f, 1.0f, 0.0f);
        glScalef(0.7f, 0.8f + 0.6f * (k % 3), 0.7f);
        glColor3f(0.9f - 0.6f * t, 0.3f + 0.5f * (k % 2), 0.2f + 0.7f * t);
        glNormal3f(0.0f, 0.0f, 1.0f); /* the same current normal every frame */
        glCallList(1);
        glPopMatrix();
      }
    }
    if (overlay && rank == 0) {
      /* A translucent panel over the left of the window, drawn last in window coordinates. */
      glMatrixMode(GL_PROJECTION);
      glPushMatrix();
      glLoadIdentity();
      glOrtho(0, w, 0, h, -1, 1);
      glMatrixMode(GL_MODELVIEW);
      glPushMatrix();
      glLoadIdentity();
      glDisable(GL_LIGHTING);
      glDisable(GL_DEPTH_TEST);
      glEnable(GL_BLEND);
      glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
      glColor4f(0.1f, 0.15f, 0.3f, 0.4f);
      glBegin(GL_QUADS);
      glVertex2f(0.05f * w, 0.1f * h);
      glVertex2f(0.4f * w, 0.1f * h);
      glVertex2f(0.4f * w, 0.9f * h);
      glVertex2f(0.05f * w, 0.9f * h);
      glEnd();
      glDisable(GL_BLEND);
      glEnable(GL_DEPTH_TEST);
      glEnable(GL_LIGHTING);
      glPopMatrix();
      glMatrixMode(GL_PROJECTION);
      glPopMatrix();
      glMatrixMode(GL_MODELVIEW);
    }
    /* IceT's draw callback: colour, then depth. */
    glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, color);
    glReadPixels(0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, depth);
    if (rank == 0 && mesh_path) printf("icet_like: frame %d: %.4f s\n", frame, MPI_Wtime() - start);
    MPI_Gather(color, 4 * (int)n, MPI_UNSIGNED_CHAR, colors, 4 * (int)n, MPI_UNSIGNED_CHAR, 0, MPI_COMM_WORLD);
    MPI_Gather(depth, (int)n, MPI_FLOAT, depths, (int)n, MPI_FLOAT, 0, MPI_COMM_WORLD);
    if (rank == 0) {
      for (size_t i = 0; i < n; i++) {
        int best = 0;
        for (int r = 1; r < size; r++)
          if (depths[r * n + i] < depths[best * n + i]) best = r;
        memcpy(image + 4 * i, colors + 4 * (best * n + i), 4);
      }
    }
  }
  if (rank == 0) {
    write_png(argv[1], image, w, h);
    printf("icet_like: %d ranks, %d frames, %dx%d, %d objects, wrote %s\n", size, frames, w, h, objects, argv[1]);
  }
  OSMesaDestroyContext(ctx);
  MPI_Finalize();
  return 0;
}
