/* The wavy, lit 80 x 80 grid two OSMesa helpers draw (client_arrays.c from client arrays,
 * immediate_grid.c in immediate mode): its vertices, the camera and light it is seen with, and
 * an 8 x 8 grid of a frame's pixels printed for the test to compare with Mesa's. */
#ifndef GLRAY_TEST_WAVY_GRID_H
#define GLRAY_TEST_WAVY_GRID_H
#include <math.h>
#include <stdio.h>

/* The grid's side, in vertices (a helper may ask for a bigger grid before including this). */
#ifndef N
#define N 80
#endif

static float pos[N * N * 3], nrm[N * N * 3];
static unsigned char col[N * N * 4];

static float height(float x, float y) { return 0.15f * sinf(5 * x) * cosf(4 * y); }

static void make_grid(float raise) {
  for (int j = 0; j < N; j++)
    for (int i = 0; i < N; i++) {
      int k = j * N + i;
      float x = -1 + 2.0f * i / (N - 1), y = -1 + 2.0f * j / (N - 1);
      float band = (j > N / 3 && j < N / 2) ? raise : 0;
      pos[3 * k] = x, pos[3 * k + 1] = y, pos[3 * k + 2] = height(x, y) + band;
      /* the normal of the height field, not normalized (GL_NORMALIZE is on) */
      nrm[3 * k] = -0.75f * cosf(5 * x) * cosf(4 * y), nrm[3 * k + 1] = 0.6f * sinf(5 * x) * sinf(4 * y);
      nrm[3 * k + 2] = 1;
      col[4 * k] = (unsigned char)(255 * i / (N - 1)), col[4 * k + 1] = (unsigned char)(255 * j / (N - 1));
      col[4 * k + 2] = 128, col[4 * k + 3] = 255;
    }
}

static void print_frame(int f, const unsigned char *buf, int w, int h) {
  printf("frame %d:", f);
  for (int y = 0; y < 8; y++)
    for (int x = 0; x < 8; x++) {
      const unsigned char *p = buf + 4 * (w * (h * (2 * y + 1) / 16) + w * (2 * x + 1) / 16);
      printf(" %d,%d,%d", p[0], p[1], p[2]);
    }
  printf("\n");
}

/* The camera, a light at infinity, lighting by the vertices' colours, depth test. */
static void view_grid(void) {
  glMatrixMode(GL_PROJECTION);
  glFrustum(-0.5, 0.5, -0.5, 0.5, 1, 10);
  glMatrixMode(GL_MODELVIEW);
  glTranslatef(0, 0, -2.2f);
  glRotatef(-25, 1, 0, 0);
  GLfloat dir[4] = {0.3f, 0.5f, 1, 0};
  glLightfv(GL_LIGHT0, GL_POSITION, dir);
  glEnable(GL_LIGHTING), glEnable(GL_LIGHT0), glEnable(GL_NORMALIZE), glEnable(GL_DEPTH_TEST);
  glEnable(GL_COLOR_MATERIAL);
  glClearColor(0.1f, 0.1f, 0.2f, 1);
}
#endif
