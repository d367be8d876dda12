/* An OSMesa program that gives per-vertex attributes in every form GL has for them, one form a
 * cell of an 8 x 8 grid of squares, as old programs mix them: scalar and vector, bytes, shorts,
 * ints, floats, doubles, signed and unsigned.
 *   0: colours, glColor{3,4}{b,s,i,f,d,ub,us,ui}{,v} (integer colours are normalised);
 *   1: positions, glVertex{2,3,4}{s,i,f,d}{,v};
 *   2: normals under a light, glNormal3{b,s,i,f,d}{,v} (integer normals are normalised);
 *   3: texture coordinates, glTexCoord{1,2,3,4}{s,i,f,d}{,v} and the same as
 *      glMultiTexCoord*(GL_TEXTURE0), picking a texel of an 8 x 8 texture each;
 *   4: frame 0's colours compiled into a display list, then called; the list then gives a
 *      colour outside glBegin and the second unit's coordinates inside one (calls a list keeps
 *      as calls, not in the mesh it makes), for a quad over the last cell;
 *   5: frame 2's normals in a list compiled and executed at once;
 *   6: a colour given, a core-profile context made current and the first one again, then a
 *      quad over the window in that colour (the colour belongs to the first context).
 * glray hands these commands to capture typed when no trace file is written, and as recorded
 * calls when one is. Prints an 8 x 8 grid of pixels per frame (the cells' centres) and the
 * errors glGetError reports, among them a glMultiTexCoord of a unit that does not exist.
 * Built by tests/raytrace.rs with cc. */
#include <math.h>

#include "gl_functions.h"

#define W 128
#define CELL (W / 8)

/* Colour k's components, each in [0, 1]. */
static double red(int k) { return (k * 5 % 8) / 7.0; }
static double green(int k) { return (k * 3 % 8) / 7.0; }
static double blue(int k) { return (k + k / 8) % 4 / 3.0; }

#define RGB(T, M) (T)(r * (M)), (T)(g * (M)), (T)(b * (M))
#define COLOR3(i, suf, T, M)                                                                     \
  case 2 * (i): glColor3##suf(RGB(T, M)); break;                                               \
  case 2 * (i) + 1: { T v[] = {RGB(T, M)}; glColor3##suf##v(v); break; }
#define COLOR4(i, suf, T, M)                                                                     \
  case 16 + 2 * (i): glColor4##suf(RGB(T, M), (T)(M)); break;                                  \
  case 16 + 2 * (i) + 1: { T v[] = {RGB(T, M), (T)(M)}; glColor4##suf##v(v); break; }

static void color_form(int form, double r, double g, double b) {
  switch (form) {
    COLOR3(0, b, GLbyte, 127) COLOR3(1, s, GLshort, 32767) COLOR3(2, i, GLint, 2147483647.0)
    COLOR3(3, f, GLfloat, 1) COLOR3(4, d, GLdouble, 1) COLOR3(5, ub, GLubyte, 255)
    COLOR3(6, us, GLushort, 65535) COLOR3(7, ui, GLuint, 4294967295.0)
    COLOR4(0, b, GLbyte, 127) COLOR4(1, s, GLshort, 32767) COLOR4(2, i, GLint, 2147483647.0)
    COLOR4(3, f, GLfloat, 1) COLOR4(4, d, GLdouble, 1) COLOR4(5, ub, GLubyte, 255)
    COLOR4(6, us, GLushort, 65535) COLOR4(7, ui, GLuint, 4294967295.0)
  }
}

#define VERTEX(i, n, suf, T, ...)                                                                \
  case 2 * (i): glVertex##n##suf(__VA_ARGS__); break;                                          \
  case 2 * (i) + 1: { T v[] = {__VA_ARGS__}; glVertex##n##suf##v(v); break; }
#define XY(T) (T)x, (T)y
#define VERTICES(i, suf, T)                                                                      \
  VERTEX(i, 2, suf, T, XY(T)) VERTEX(4 + (i), 3, suf, T, XY(T), (T)0) VERTEX(8 + (i), 4, suf, T, XY(T), (T)0, (T)1)

static void vertex_form(int form, int x, int y) {
  switch (form) { VERTICES(0, s, GLshort) VERTICES(1, i, GLint) VERTICES(2, f, GLfloat) VERTICES(3, d, GLdouble) }
}

#define NORMAL(i, suf, T, M)                                                                     \
  case 2 * (i): glNormal3##suf((T)(x * (M)), (T)(y * (M)), (T)(z * (M))); break;               \
  case 2 * (i) + 1: { T v[] = {(T)(x * (M)), (T)(y * (M)), (T)(z * (M))}; glNormal3##suf##v(v); break; }

static void normal_form(int form, double x, double y, double z) {
  switch (form) {
    NORMAL(0, b, GLbyte, 127) NORMAL(1, s, GLshort, 32767) NORMAL(2, i, GLint, 2147483647.0)
    NORMAL(3, f, GLfloat, 1) NORMAL(4, d, GLdouble, 1)
  }
}

/* Texture coordinates (s, t) in texels times two plus one (odd integers: exact in every
 * type), scaled into [0, 1] by the texture matrix; forms 32-63 are glMultiTexCoord's. */
#define TEX(i, n, suf, T, ...)                                                                   \
  case 2 * (i): glTexCoord##n##suf(__VA_ARGS__); break;                                        \
  case 2 * (i) + 1: { T v[] = {__VA_ARGS__}; glTexCoord##n##suf##v(v); break; }                 \
  case 32 + 2 * (i): glMultiTexCoord##n##suf(GL_TEXTURE0, __VA_ARGS__); break;                 \
  case 32 + 2 * (i) + 1: { T v[] = {__VA_ARGS__}; glMultiTexCoord##n##suf##v(GL_TEXTURE0, v); break; }
#define TEXES(i, suf, T)                                                                         \
  TEX(i, 1, suf, T, (T)s) TEX(4 + (i), 2, suf, T, (T)s, (T)t) TEX(8 + (i), 3, suf, T, (T)s, (T)t, (T)0)        \
  TEX(12 + (i), 4, suf, T, (T)s, (T)t, (T)0, (T)1)

static void texcoord_form(int form, int s, int t) {
  switch (form) { TEXES(0, s, GLshort) TEXES(1, i, GLint) TEXES(2, f, GLfloat) TEXES(3, d, GLdouble) }
}

/* The cells, one quad each: frame `f`'s attribute in form k, then the corners (in form k in
 * frame 1, else glVertex2i). */
static void cells(int f) {
  glBegin(GL_QUADS);
  for (int k = 0; k < 64; k++) {
    int x = CELL * (k % 8), y = CELL * (k / 8);
    if (f == 0 && k < 32) color_form(k, red(k), green(k), blue(k));
    if (f == 1) glColor3d(red(k), green(k), blue(k));
    if (f == 2 && k < 10) {
      double a = 0.6 * k;
      normal_form(k, 0.5 * cos(a), 0.5 * sin(a), 0.7);
    }
    if (f == 3) texcoord_form(k, 2 * (k % 8) + 1, 2 * (k * 3 % 8) + 1);
    if (f == 1 && k >= 24) continue;
    int corners[4][2] = {{x, y}, {x + CELL, y}, {x + CELL, y + CELL}, {x, y + CELL}};
    for (int c = 0; c < 4; c++) {
      if (f == 1) vertex_form(k, corners[c][0], corners[c][1]);
      else glVertex2i(corners[c][0], corners[c][1]);
    }
  }
  glEnd();
}

static void print_frame(int f, const unsigned char *buf) {
  printf("frame %d:", f);
  for (int k = 0; k < 64; k++) {
    const unsigned char *p = buf + 4 * (W * (CELL * (k / 8) + CELL / 2) + CELL * (k % 8) + CELL / 2);
    printf(" %d,%d,%d", p[0], p[1], p[2]);
  }
  printf("\n");
}

int main(void) {
  unsigned char *buf;
  OSMesaContext c = osmesa_context(W, W, &buf);
  window_projection(W, W);
  GLubyte texels[8 * 8 * 3];
  for (int k = 0; k < 64; k++) texels[3 * k] = 32 * (k % 8), texels[3 * k + 1] = 32 * (k / 8), texels[3 * k + 2] = 200;
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, 8, 8, 0, GL_RGB, GL_UNSIGNED_BYTE, texels);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glMatrixMode(GL_TEXTURE);
  glScalef(1.0f / 16, 1.0f / 16, 1);
  glMatrixMode(GL_MODELVIEW);
  GLfloat light[4] = {0.3f, 0.4f, 1, 0};
  glLightfv(GL_LIGHT0, GL_POSITION, light);
  glEnable(GL_LIGHT0);
  glEnable(GL_NORMALIZE);
  GLuint lists = glGenLists(2);
  for (int f = 0; f < 6; f++) {
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (f == 2 || f == 5) glEnable(GL_LIGHTING);
    if (f == 3) glEnable(GL_TEXTURE_2D), glColor3f(1, 1, 1);
    if (f == 4) {
      glNewList(lists, GL_COMPILE);
      cells(0);
      glColor3ub(10, 200, 30);
      glBegin(GL_QUADS);
      glMultiTexCoord2f(GL_TEXTURE1, 0.5f, 0.5f);
      glVertex2i(W - CELL, W - CELL), glVertex2i(W, W - CELL), glVertex2i(W, W), glVertex2i(W - CELL, W);
      glEnd();
      glEndList();
      glCallList(lists);
    } else if (f == 5) {
      glNewList(lists + 1, GL_COMPILE_AND_EXECUTE);
      cells(2);
      glEndList();
    } else {
      cells(f);
    }
    glDisable(GL_LIGHTING);
    glDisable(GL_TEXTURE_2D);
    glFinish();
    print_frame(f, buf);
  }
  int core_attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_PROFILE, OSMESA_CORE_PROFILE, OSMESA_CONTEXT_MAJOR_VERSION, 3,
                        OSMESA_CONTEXT_MINOR_VERSION, 3, 0};
  OSMesaContext core = OSMesaCreateContextAttribs(core_attribs, NULL);
  unsigned char core_buf[16 * 16 * 4];
  glColor3ub(250, 20, 120);
  if (!core || !OSMesaMakeCurrent(core, core_buf, GL_UNSIGNED_BYTE, 16, 16) ||
      !OSMesaMakeCurrent(c, buf, GL_UNSIGNED_BYTE, W, W)) {
    printf("no core profile context\n");
    return 1;
  }
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glBegin(GL_QUADS);
  glVertex2i(0, 0), glVertex2i(W, 0), glVertex2i(W, W), glVertex2i(0, W);
  glEnd();
  glFinish();
  print_frame(6, buf);
  printf("error 0x%x\n", glGetError());
  glMultiTexCoord2f(GL_TEXTURE0 + 40, 0, 0);
  printf("unit 40 error 0x%x\n", glGetError());
  OSMesaDestroyContext(core);
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
