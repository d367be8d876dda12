/* An OSMesa program that animates a simulation's time steps, as a visualization program
 * stepping through time does: every frame the surface of the next step, a lit 200 x 200 grid
 * (79,202 triangles) whose band rises step by step, its positions, normals and colours put
 * into buffer objects anew (glBufferData) and drawn with glDrawElements:
 *   0-3: a new step each frame;
 *   4, 5: the program stays on step 3 (its buffers drawn again as they are);
 *   6: a new step again.
 * Under glray (`bvh` setting `auto`) each step's mesh, the same triangles moved, gets the last
 * step's BVH refitted (`refits`). Built with -DTRIM, each step draws two triangles fewer than
 * the last: no tree to refit, and a mesh replaced frame after frame gets a BVH built fast from
 * the second step on; once the program stays on a step, the next one's is built by SAH again
 * (`fast_builds`). GLRAY_STATS also says what memory is kept for the next step (`kept_mb`).
 * Prints an 8 x 8 grid of pixels per frame. Built by tests/raytrace.rs with cc (-DN=640 for
 * arrays big enough to be kept). */
#ifndef N
#define N 200
#endif
#ifdef TRIM
#define TRIMMED(step) (6 * 2 * (step))
#else
#define TRIMMED(step) 0
#endif
#include "gl_functions.h"
#include "wavy_grid.h"

static unsigned int idx[(N - 1) * (N - 1) * 6];

int main(void) {
  int w = 96, h = 96;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  load_gl_functions();
  view_grid();
  int n = 0;
  for (int j = 0; j + 1 < N; j++)
    for (int i = 0; i + 1 < N; i++) {
      unsigned int k = j * N + i;
      unsigned int t[6] = {k, k + 1, k + N + 1, k, k + N + 1, k + N};
      for (int e = 0; e < 6; e++) idx[n++] = t[e];
    }
  GLuint b[4];
  glGenBuffers(4, b);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, b[3]);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, sizeof idx, idx, GL_STATIC_DRAW);
  glEnableClientState(GL_VERTEX_ARRAY), glEnableClientState(GL_NORMAL_ARRAY), glEnableClientState(GL_COLOR_ARRAY);

  static const int step_of_frame[7] = {0, 1, 2, 3, 3, 3, 4};
  for (int f = 0; f < 7; f++) {
    int same = f > 0 && step_of_frame[f] == step_of_frame[f - 1];
    make_grid(0.06f * step_of_frame[f]);
    for (int k = 0; k < N * N; k++) col[4 * k + 2] = (unsigned char)(40 * step_of_frame[f]);
    if (same) goto draw;
    glBindBuffer(GL_ARRAY_BUFFER, b[0]);
    glBufferData(GL_ARRAY_BUFFER, sizeof pos, pos, GL_DYNAMIC_DRAW);
    glVertexPointer(3, GL_FLOAT, 0, 0);
    glBindBuffer(GL_ARRAY_BUFFER, b[1]);
    glBufferData(GL_ARRAY_BUFFER, sizeof nrm, nrm, GL_DYNAMIC_DRAW);
    glNormalPointer(GL_FLOAT, 0, 0);
    glBindBuffer(GL_ARRAY_BUFFER, b[2]);
    glBufferData(GL_ARRAY_BUFFER, sizeof col, col, GL_DYNAMIC_DRAW);
    glColorPointer(4, GL_UNSIGNED_BYTE, 0, 0);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
  draw:
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glDrawElements(GL_TRIANGLES, n - TRIMMED(step_of_frame[f]), GL_UNSIGNED_INT, 0);
    glFinish();
    print_frame(f, buf, w, h);
  }
  printf("error 0x%x\n", glGetError());
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
