/* An OSMesa program that draws with glLogicOp (GL_COLOR_LOGIC_OP): a square of one colour,
 * then squares over it combined bit by bit with what is there, XOR, AND_REVERSE (source and
 * not destination: xscreensaver's quasicrystal clips its colours so), OR and INVERT, the
 * blending left on (GL ignores it while the logic op is on). Prints the colour of each
 * square's part over the first and beside it. Built by tests/raytrace.rs with cc. */
#include "gl_functions.h"

static void rect(float x0, float y0, float x1, float y1) {
  glBegin(GL_QUADS);
  glVertex2f(x0, y0);
  glVertex2f(x1, y0);
  glVertex2f(x1, y1);
  glVertex2f(x0, y1);
  glEnd();
}

int main(void) {
  int w = 64, h = 64;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  window_projection(w, h);
  glClearColor(0.2f, 0.4f, 0.6f, 1);
  glClear(GL_COLOR_BUFFER_BIT);
  glColor3ub(0xF0, 0x3C, 0x99);
  rect(0, 0, 32, 64);
  glEnable(GL_BLEND);
  glBlendFunc(GL_ONE, GL_ONE);
  glEnable(GL_COLOR_LOGIC_OP);
  const GLenum ops[] = {GL_XOR, GL_AND_REVERSE, GL_OR, GL_INVERT};
  const char *names[] = {"xor", "and_reverse", "or", "invert"};
  for (int k = 0; k < 4; k++) {
    glLogicOp(ops[k]);
    glColor3ub(0x5A, 0xC3, 0x0F);
    rect(16, 4 + 15 * k, 48, 14 + 15 * k);
  }
  glDisable(GL_COLOR_LOGIC_OP);
  glFinish();
  for (int k = 0; k < 4; k++) {
    const unsigned char *over = buf + 4 * (w * (9 + 15 * k) + 24);
    const unsigned char *beside = buf + 4 * (w * (9 + 15 * k) + 40);
    printf("%s over %d %d %d beside %d %d %d\n", names[k], over[0], over[1], over[2], beside[0], beside[1], beside[2]);
  }
  printf("error 0x%x\n", glGetError());
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
