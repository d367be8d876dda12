/* An OSMesa program that draws a big lit surface from client arrays (its own memory: no buffer
 * object), as older VTK and VisIt do, over six frames:
 *   0: a wavy 80 x 80 grid through glDrawElements (12,482 triangles);
 *   1: the same bytes again;
 *   2: the same arrays changed in place (colours of one half, heights of a band), same pointers;
 *   3: the grid as separate triangles through glDrawArrays, from memory allocated anew;
 *   4: the same, its arrays turned off and back on by glPushClientAttrib/glPopClientAttrib;
 *   5: the same triangles from one glInterleavedArrays array of floats.
 * glray keeps a big client draw's mesh by the bytes it reads: frame 1 reuses it, frame 2 must
 * not. Prints an 8 x 8 grid of pixels per frame. Built by tests/raytrace.rs with cc. */
#include <math.h>
#include <string.h>

#include "gl_functions.h"
#include "wavy_grid.h"

static unsigned int idx[(N - 1) * (N - 1) * 6 - 2];

int main(void) {
  int w = 96, h = 96;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  view_grid();

  make_grid(0);
  int n = 0;
  for (int j = 0; j + 1 < N; j++)
    for (int i = 0; i + 1 < N; i++) {
      unsigned int k = j * N + i;
      unsigned int t[6] = {k, k + 1, k + N + 1, k, k + N + 1, k + N};
      for (int e = 0; e < 6 && n < (int)(sizeof idx / sizeof idx[0]); e++) idx[n++] = t[e];
    }
  glEnableClientState(GL_VERTEX_ARRAY), glEnableClientState(GL_NORMAL_ARRAY), glEnableClientState(GL_COLOR_ARRAY);
  glVertexPointer(3, GL_FLOAT, 0, pos), glNormalPointer(GL_FLOAT, 0, nrm), glColorPointer(4, GL_UNSIGNED_BYTE, 0, col);

  for (int f = 0; f < 3; f++) {
    if (f == 2) {
      make_grid(0.2f);
      for (int k = 0; k < N * N / 2; k++) col[4 * k + 2] = 20;
    }
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glDrawElements(GL_TRIANGLES, n, GL_UNSIGNED_INT, idx);
    glFinish();
    print_frame(f, buf, w, h);
  }

  /* The same triangles, each corner its own element, in memory allocated anew. */
  float *p = malloc(sizeof(float) * 3 * n), *q = malloc(sizeof(float) * 3 * n);
  unsigned char *r = malloc(4 * (size_t)n);
  for (int e = 0; e < n; e++) {
    memcpy(p + 3 * e, pos + 3 * idx[e], 3 * sizeof(float));
    memcpy(q + 3 * e, nrm + 3 * idx[e], 3 * sizeof(float));
    memcpy(r + 4 * e, col + 4 * idx[e], 4);
  }
  glVertexPointer(3, GL_FLOAT, 0, p), glNormalPointer(GL_FLOAT, 0, q), glColorPointer(4, GL_UNSIGNED_BYTE, 0, r);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glDrawArrays(GL_TRIANGLES, 0, n);
  glFinish();
  print_frame(3, buf, w, h);

  /* 4: the arrays turned off and back on by the client attribute stack (glray reads them back
   * from GL after glPopClientAttrib); 5: the same triangles from one interleaved array. */
  glPushClientAttrib(GL_CLIENT_VERTEX_ARRAY_BIT);
  glDisableClientState(GL_VERTEX_ARRAY), glDisableClientState(GL_NORMAL_ARRAY), glDisableClientState(GL_COLOR_ARRAY);
  glPopClientAttrib();
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glDrawArrays(GL_TRIANGLES, 0, n);
  glFinish();
  print_frame(4, buf, w, h);
  float *v = malloc(sizeof(float) * 10 * n);
  for (int e = 0; e < n; e++) {
    for (int k = 0; k < 4; k++) v[10 * e + k] = r[4 * e + k] / 255.0f;
    memcpy(v + 10 * e + 4, q + 3 * e, 3 * sizeof(float));
    memcpy(v + 10 * e + 7, p + 3 * e, 3 * sizeof(float));
  }
  glDisableClientState(GL_VERTEX_ARRAY), glDisableClientState(GL_NORMAL_ARRAY), glDisableClientState(GL_COLOR_ARRAY);
  glInterleavedArrays(GL_C4F_N3F_V3F, 0, v);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glDrawArrays(GL_TRIANGLES, 0, n);
  glFinish();
  print_frame(5, buf, w, h);
  printf("error 0x%x\n", glGetError());
  OSMesaDestroyContext(c);
  free(buf), free(p), free(q), free(r), free(v);
  return 0;
}
