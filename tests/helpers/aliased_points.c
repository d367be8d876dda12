/* An OSMesa program that draws aliased points (GL_POINTS, no GL_POINT_SMOOTH) of sizes 1 to 3.5,
 * a grid of them at positions that step through a pixel by tenths (halves included), and prints
 * for each size the pixels they light. GL draws a point as a square of its size rounded to whole
 * pixels (Mesa rounds halves down), centred on a pixel's centre (odd sizes) or corner (even
 * ones): its edges never fall on a pixel centre. Built by tests/raytrace.rs with cc. */
#include "gl_functions.h"

int main(void) {
  int w = 64, h = 64;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  window_projection(w, h);
  const float sizes[] = {1, 1.5f, 2, 2.5f, 2.7f, 3.5f};
  for (int k = 0; k < 6; k++) {
    glClear(GL_COLOR_BUFFER_BIT);
    glPointSize(sizes[k]);
    glColor3f(1, 1, 1);
    glBegin(GL_POINTS);
    for (int i = 0; i < 10; i++)
      for (int j = 0; j < 10; j++) glVertex2f(3 + 6 * i + 0.1f * i, 3 + 6 * j + 0.1f * j);
    glEnd();
    glFinish();
    printf("size %.1f:", sizes[k]);
    for (int i = 0; i < w * h; i++)
      if (buf[4 * i]) printf(" %d", i);
    printf("\n");
  }
  printf("error 0x%x\n", glGetError());
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
