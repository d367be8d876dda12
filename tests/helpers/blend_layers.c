/* An OSMesa program that adds layers up with blending (GL_SRC_ALPHA, GL_ONE), as xscreensaver's
 * glblur adds its blur: two quads drawn over each other in one glBegin(GL_QUADS) on the left
 * half of the window (each pixel gets both), and one quad on the right whose diagonal runs
 * through pixel centres (each pixel of the diagonal gets one of its two triangles, by GL's fill
 * rule). Prints the colour at a point of the left, at a point of the right quad's diagonal and
 * at one off it. Built by tests/raytrace.rs with cc. */
#include "gl_functions.h"

static void quad(float x0, float y0, float x1, float y1) {
  glVertex2f(x0, y0);
  glVertex2f(x1, y0);
  glVertex2f(x1, y1);
  glVertex2f(x0, y1);
}

int main(void) {
  int w = 64, h = 64;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  window_projection(w, h);
  glClear(GL_COLOR_BUFFER_BIT);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE);
  glEnable(GL_BLEND);
  glBegin(GL_QUADS);
  glColor4f(0.5f, 0.25f, 0.125f, 0.5f);
  quad(0, 0, 32, 64);
  quad(0, 0, 32, 64);
  glEnd();
  glBegin(GL_QUADS);
  glColor4f(0.5f, 0.5f, 0.5f, 0.5f);
  quad(32, 0, 64, 32); /* the diagonal (32,0)-(64,32) splits it: y = x - 32 */
  glEnd();
  glFinish();
  int at[3][2] = {{10, 10}, {40, 8}, {50, 5}};
  const char *where[3] = {"layers", "diagonal", "beside"};
  for (int k = 0; k < 3; k++) {
    const unsigned char *p = buf + 4 * (w * at[k][1] + at[k][0]);
    printf("%s %d %d %d\n", where[k], p[0], p[1], p[2]);
  }
  printf("error 0x%x\n", glGetError());
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
