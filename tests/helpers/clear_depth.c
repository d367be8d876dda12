/* An OSMesa program that clears the depth buffer to values other than 1 (glClearDepth), in four
 * frames: a clear to 0.7 that a far square (window depth 0.8333) fails against; reversed depth
 * (a clear to 0 with GL_GREATER), where the farther of two squares wins; a depth-only clear to
 * 0.6 between two draws; and a clear to 0.7 within a scissor box (the left half). The near
 * square (window depth 0.5556) is small and red, the far one large and green. Prints, per
 * frame, the colour and depth (glReadPixels) at the centre, at a point only the far square
 * covers, at a point of the left half only the far square covers, and at a corner no draw
 * covers. Built by tests/raytrace.rs with cc. */
#include "gl_functions.h"

static void near_square(void) {
  glColor3f(1, 0, 0);
  square(0.5f, 0);
}

static void far_square(void) {
  glColor3f(0, 1, 0);
  square(3, -2);
}

static void report(const char *name, int w, int h, const unsigned char *buf) {
  int at[4][2] = {{w / 2, h / 2}, {w / 2 + 12, h / 2}, {w / 2 - 12, h / 2}, {2, 2}};
  const char *where[4] = {"centre", "right", "left", "corner"};
  glFinish();
  for (int k = 0; k < 4; k++) {
    const unsigned char *p = buf + 4 * (w * at[k][1] + at[k][0]);
    float d;
    glReadPixels(at[k][0], at[k][1], 1, 1, GL_DEPTH_COMPONENT, GL_FLOAT, &d);
    printf("%s %s %d %d %d depth %.4f\n", name, where[k], p[0], p[1], p[2], d);
  }
}

int main(void) {
  int w = 64, h = 64;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  glMatrixMode(GL_PROJECTION);
  glFrustum(-1, 1, -1, 1, 1, 10);
  glMatrixMode(GL_MODELVIEW);
  glTranslatef(0, 0, -2);
  glEnable(GL_DEPTH_TEST);

  glClearDepth(0.7);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  far_square();
  near_square();
  report("cleared-to-0.7", w, h, buf);

  glClearDepth(0.0);
  glDepthFunc(GL_GREATER);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  near_square();
  far_square();
  report("reversed", w, h, buf);

  glDepthFunc(GL_LESS);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  far_square();
  glClearDepth(0.6);
  glClear(GL_DEPTH_BUFFER_BIT);
  near_square();
  report("between-draws", w, h, buf);

  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_SCISSOR_TEST);
  glScissor(0, 0, w / 2, h);
  glClearDepth(0.7);
  glClear(GL_DEPTH_BUFFER_BIT);
  glDisable(GL_SCISSOR_TEST);
  far_square();
  report("scissored", w, h, buf);

  float value = -1;
  glGetFloatv(GL_DEPTH_CLEAR_VALUE, &value);
  printf("clear value %.2f error 0x%x\n", value, glGetError());
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
