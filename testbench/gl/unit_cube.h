/* The unit cube of the GL test programs: four vertices a face, counter-
 * clockwise seen from outside (+z, -z, +x, -x, +y, -y), so that a face's
 * triangles are (b, b+1, b+2) and (b, b+2, b+3) from its first vertex b. */
#ifndef RBCD_TESTBENCH_GL_UNIT_CUBE_H
#define RBCD_TESTBENCH_GL_UNIT_CUBE_H

static const float cube[24][3] = {
    {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1},   /* +z */
    {0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0},   /* -z */
    {1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1},   /* +x */
    {0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0},   /* -x */
    {0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0},   /* +y */
    {0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1},   /* -y */
};

#endif
