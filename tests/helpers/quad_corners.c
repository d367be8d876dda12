/* An OSMesa program that draws a quad whose corners differ, in each way a program can give it,
 * and prints the colour at its centre: which diagonal cuts a quad is the implementation's
 * choice, and the centre lies on one diagonal or the other. Mesa cuts quads from glBegin/glEnd
 * and glDrawArrays along corners 0-2, and quads from glDrawElements and display lists (which it
 * compiles into indexed draws) along 1-3; and along 1-3 too a glBegin/glEnd whose quad reaches
 * outside the view volume (its clipping path cuts them so).
 * Then a quad whose texture coordinates come from GL_SPHERE_MAP with a normal shorter than 1
 * (xscreensaver's blocktube gives 0.7): GL reflects the eye vector about the normal as given,
 * not normalized. Prints a row of its colours. Built by tests/raytrace.rs with cc. */
#include "gl_functions.h"

static const float P[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
static const float C[4][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, 0}};
static const unsigned I[4] = {0, 1, 2, 3};

static void quad_scaled(float scale) {
  glBegin(GL_QUADS);
  for (int i = 0; i < 4; i++) {
    glColor3fv(C[i]);
    glVertex2f(P[i][0] * scale, P[i][1] * scale);
  }
  glEnd();
}

static void quad(void) { quad_scaled(1); }

int main(void) {
  int w = 64, h = 64;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  const char *ways[] = {"glBegin", "glDrawArrays", "glDrawElements", "list of glBegin", "list of glDrawArrays",
                        "glBegin reaching outside the view"};
  glVertexPointer(2, GL_FLOAT, 0, P);
  glColorPointer(3, GL_FLOAT, 0, C);
  glNewList(1, GL_COMPILE);
  quad();
  glEndList();
  glEnableClientState(GL_VERTEX_ARRAY);
  glEnableClientState(GL_COLOR_ARRAY);
  glNewList(2, GL_COMPILE);
  glDrawArrays(GL_QUADS, 0, 4);
  glEndList();
  for (int k = 0; k < 6; k++) {
    glClear(GL_COLOR_BUFFER_BIT);
    if (k == 0) quad();
    if (k == 1) glDrawArrays(GL_QUADS, 0, 4);
    if (k == 2) glDrawElements(GL_QUADS, 4, GL_UNSIGNED_INT, I);
    if (k == 3) glCallList(1);
    if (k == 4) glCallList(2);
    if (k == 5) quad_scaled(1.5f);
    glFinish();
    const unsigned char *p = buf + 4 * (w * (h / 2) + w / 2);
    printf("%s: centre %d %d %d\n", ways[k], p[0], p[1], p[2]);
  }
  glDisableClientState(GL_VERTEX_ARRAY);
  glDisableClientState(GL_COLOR_ARRAY);

  /* The sphere-mapped quad: a texture whose red grows with s and green with t. */
  unsigned char tex[16 * 16 * 4];
  for (int t = 0; t < 16; t++)
    for (int s = 0; s < 16; s++) {
      unsigned char *texel = tex + 4 * (16 * t + s);
      texel[0] = (unsigned char)(s * 17);
      texel[1] = (unsigned char)(t * 17);
      texel[2] = 0;
      texel[3] = 255;
    }
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, 16, 16, 0, GL_RGBA, GL_UNSIGNED_BYTE, tex);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexGeni(GL_S, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP);
  glTexGeni(GL_T, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP);
  glEnable(GL_TEXTURE_GEN_S);
  glEnable(GL_TEXTURE_GEN_T);
  glEnable(GL_TEXTURE_2D);
  glMatrixMode(GL_PROJECTION);
  glFrustum(-1, 1, -1, 1, 1, 10);
  glMatrixMode(GL_MODELVIEW);
  glTranslatef(0.3f, 0.2f, -2);
  glClear(GL_COLOR_BUFFER_BIT);
  glColor3f(1, 1, 1);
  glNormal3f(0, 0, 0.7f);
  glBegin(GL_QUADS);
  for (int i = 0; i < 4; i++) glVertex2fv(P[i]);
  glEnd();
  glFinish();
  printf("sphere map:");
  for (int x = 4; x < w; x += 8) {
    const unsigned char *p = buf + 4 * (w * (h / 2 + 5) + x);
    printf(" %d,%d", p[0], p[1]);
  }
  printf("\nerror 0x%x\n", glGetError());
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
