/* An OSMesa program whose display list changes state besides drawing: front face, culling,
 * shading, polygon mode, depth, blending, alpha test, line width, the current colour and
 * normal, a light (placed under a translation), materials and the light model. After
 * glCallList it asks the GL for each (and for the raster colour glRasterPos takes from the
 * current colour, which glBitmap text is drawn in, unlit and then lit by the list's light). glray takes the glCallList from
 * the real GL (the list's triangle is ray traced), so the real GL must be told what the list
 * changed, or these answers are the state from before the list. Built by tests/raytrace.rs. */
#include "gl_functions.h"

int main(void) {
  int w = 32, h = 32;
  unsigned char *buf;
  OSMesaContext c = osmesa_context(w, h, &buf);
  glEnable(GL_DEPTH_TEST);
  GLuint list = glGenLists(1);
  glNewList(list, GL_COMPILE);
  glFrontFace(GL_CW);
  glEnable(GL_CULL_FACE);
  glCullFace(GL_FRONT);
  glShadeModel(GL_FLAT);
  glPolygonMode(GL_BACK, GL_LINE);
  glDisable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glDepthMask(GL_FALSE);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glEnable(GL_ALPHA_TEST);
  glAlphaFunc(GL_GREATER, 0.25f);
  glLineWidth(3);
  glPointSize(2);
  glColor4f(1, 0.5f, 0.25f, 1);
  glNormal3f(0, 1, 0);
  glPushMatrix();
  glTranslatef(1, 2, 3);
  GLfloat at[4] = {1, 0, 0, 1}, diffuse[4] = {0.5f, 0.25f, 0.125f, 1}, spot[3] = {0, -1, -1};
  glLightfv(GL_LIGHT1, GL_POSITION, at);
  glLightfv(GL_LIGHT1, GL_SPOT_DIRECTION, spot);
  glLightfv(GL_LIGHT1, GL_DIFFUSE, diffuse);
  glLightf(GL_LIGHT1, GL_SPOT_CUTOFF, 60);
  glLightf(GL_LIGHT1, GL_QUADRATIC_ATTENUATION, 0.5f);
  glPopMatrix();
  GLfloat specular[4] = {0.75f, 0.5f, 0.25f, 1}, emission[4] = {0.1f, 0.1f, 0.2f, 1}, ambient[4] = {0.1f, 0.2f, 0.3f, 1};
  glMaterialfv(GL_FRONT, GL_SPECULAR, specular);
  glMaterialf(GL_FRONT, GL_SHININESS, 32);
  glMaterialfv(GL_BACK, GL_EMISSION, emission);
  glLightModelfv(GL_LIGHT_MODEL_AMBIENT, ambient);
  glLightModeli(GL_LIGHT_MODEL_TWO_SIDE, 1);
  glColorMaterial(GL_FRONT, GL_DIFFUSE);
  glBegin(GL_TRIANGLES);
  glVertex2f(-0.5f, -0.5f);
  glVertex2f(0, 0.5f);
  glVertex2f(0.5f, -0.5f);
  glEnd();
  glEndList();
  for (int frame = 0; frame < 2; frame++) {
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glCallList(list);
    glFinish();
  }
  GLint i[2];
  GLfloat f[4];
  glGetIntegerv(GL_FRONT_FACE, i);
  printf("front face 0x%x", i[0]);
  glGetIntegerv(GL_CULL_FACE_MODE, i);
  printf(" cull 0x%x %d", i[0], glIsEnabled(GL_CULL_FACE));
  glGetIntegerv(GL_SHADE_MODEL, i);
  printf(" shade 0x%x", i[0]);
  glGetIntegerv(GL_POLYGON_MODE, i);
  printf(" polygon 0x%x 0x%x\n", i[0], i[1]);
  glGetIntegerv(GL_DEPTH_FUNC, i);
  printf("depth %d 0x%x", glIsEnabled(GL_DEPTH_TEST), i[0]);
  glGetIntegerv(GL_DEPTH_WRITEMASK, i);
  printf(" mask %d", i[0]);
  glGetIntegerv(GL_BLEND_SRC, i);
  glGetIntegerv(GL_BLEND_DST, i + 1);
  printf(" blend %d 0x%x 0x%x", glIsEnabled(GL_BLEND), i[0], i[1]);
  glGetIntegerv(GL_ALPHA_TEST_FUNC, i);
  glGetFloatv(GL_ALPHA_TEST_REF, f);
  printf(" alpha %d 0x%x %.2f\n", glIsEnabled(GL_ALPHA_TEST), i[0], f[0]);
  glGetFloatv(GL_LINE_WIDTH, f);
  glGetFloatv(GL_POINT_SIZE, f + 1);
  printf("line %.1f point %.1f\n", f[0], f[1]);
  glGetFloatv(GL_CURRENT_COLOR, f);
  printf("colour %.2f %.2f %.2f %.2f", f[0], f[1], f[2], f[3]);
  glGetFloatv(GL_CURRENT_NORMAL, f);
  printf(" normal %.2f %.2f %.2f\n", f[0], f[1], f[2]);
  glRasterPos2f(0, 0);
  glGetFloatv(GL_CURRENT_RASTER_COLOR, f);
  printf("raster colour %.2f %.2f %.2f\n", f[0], f[1], f[2]);
  glGetLightfv(GL_LIGHT1, GL_POSITION, f);
  printf("light position %.2f %.2f %.2f %.2f", f[0], f[1], f[2], f[3]);
  glGetLightfv(GL_LIGHT1, GL_SPOT_DIRECTION, f);
  printf(" spot %.2f %.2f %.2f", f[0], f[1], f[2]);
  glGetLightfv(GL_LIGHT1, GL_DIFFUSE, f);
  printf(" diffuse %.3f %.3f %.3f", f[0], f[1], f[2]);
  glGetLightfv(GL_LIGHT1, GL_SPOT_CUTOFF, f);
  glGetLightfv(GL_LIGHT1, GL_QUADRATIC_ATTENUATION, f + 1);
  printf(" cutoff %.1f quadratic %.2f\n", f[0], f[1]);
  glGetMaterialfv(GL_FRONT, GL_SPECULAR, f);
  printf("front specular %.2f %.2f %.2f", f[0], f[1], f[2]);
  glGetMaterialfv(GL_FRONT, GL_SHININESS, f);
  printf(" shininess %.1f", f[0]);
  glGetMaterialfv(GL_BACK, GL_EMISSION, f);
  printf(" back emission %.2f %.2f %.2f\n", f[0], f[1], f[2]);
  glGetFloatv(GL_LIGHT_MODEL_AMBIENT, f);
  glGetIntegerv(GL_LIGHT_MODEL_TWO_SIDE, i);
  printf("model ambient %.2f %.2f %.2f two-sided %d", f[0], f[1], f[2], i[0]);
  glGetIntegerv(GL_COLOR_MATERIAL_FACE, i);
  glGetIntegerv(GL_COLOR_MATERIAL_PARAMETER, i + 1);
  printf(" colour material 0x%x 0x%x\n", i[0], i[1]);
  /* The raster colour lit by the list's light (at eye (2, 2, 3), shining down and back at the
   * raster position) and materials, as glBitmap text under lighting is. */
  glEnable(GL_LIGHTING);
  glEnable(GL_LIGHT1);
  glRasterPos2f(0, 0);
  glGetFloatv(GL_CURRENT_RASTER_COLOR, f);
  printf("lit raster colour %.3f %.3f %.3f\n", f[0], f[1], f[2]);
  glDisable(GL_LIGHTING);
  printf("error 0x%x\n", glGetError());
  OSMesaDestroyContext(c);
  free(buf);
  return 0;
}
