/* An OSMesa program that clears the depth buffer alone between two draws, as xscreensaver's
 * skytentacles does before each tentacle: a red square near the eye, glClear(GL_DEPTH_BUFFER_BIT),
 * then a smaller green square farther away. GL draws the green one over the red (its depth is
 * tested against the cleared depth only), and a pixel no draw covers after the clear keeps the
 * red but has the cleared depth. Prints the colour and depth (glReadPixels) at the centre and
 * at a point of the red square outside the green one. Built by tests/raytrace.rs with cc. */
#include "gl_functions.h"

int main(void) {
  int w = 64, h = 64;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  glMatrixMode(GL_PROJECTION);
  glFrustum(-1, 1, -1, 1, 1, 10);
  glMatrixMode(GL_MODELVIEW);
  glEnable(GL_DEPTH_TEST);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glTranslatef(0, 0, -2);
  glColor3f(1, 0, 0);
  square(1, 0);
  glClear(GL_DEPTH_BUFFER_BIT);
  glColor3f(0, 1, 0);
  square(1, -2);
  glFinish();
  int at[2][2] = {{w / 2, h / 2}, {w / 2 + 12, h / 2}};
  for (int k = 0; k < 2; k++) {
    const unsigned char *p = buf + 4 * (w * at[k][1] + at[k][0]);
    float d;
    glReadPixels(at[k][0], at[k][1], 1, 1, GL_DEPTH_COMPONENT, GL_FLOAT, &d);
    printf("%s %d %d %d depth %.4f\n", k ? "edge" : "centre", p[0], p[1], p[2], d);
  }
  printf("error 0x%x\n", glGetError());
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
