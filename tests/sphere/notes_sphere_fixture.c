/*
 * Test fixture: the lit-sphere program of the course notes (§1), as the notes list it, so that the
 * kit's stage 1 can be compared with what OpenGL's fixed-function pipeline really draws for it.
 * Written for tests/sphere/test_notes_program.py; not shipped to students.
 *
 * Changed from the listing, and nothing else:
 *   1. the listing's glClearColor(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT) is the glClear it means;
 *   2. the listing's eight-argument gluLookAt gets its ninth argument: up = (0, 1, 0);
 *   3. the window size comes from the command line (default 500 500, as the notes' program);
 *   4. after the first frame is drawn, display() writes it to the PPM file named by the third
 *      argument (binary P6, top row first) and exits.
 * Every other call, value and its order is the notes': the light position is set in display(),
 * after glLoadIdentity() and gluLookAt(), so the modelview matrix moves it into eye space.
 */
#include <stdio.h>
#include <stdlib.h>
#include <GL/gl.h>
#include <GL/glu.h>
#include <GL/glut.h>

static int window_width = 500, window_height = 500;
static const char *frame_path = NULL;

/* Change 4: read back what display() drew and leave. */
static void dump_frame_and_exit(void) {
    GLint viewport[4];
    glGetIntegerv(GL_VIEWPORT, viewport);
    int w = viewport[2], h = viewport[3];
    unsigned char *pixels = malloc((size_t)w * h * 3);
    if (!pixels) exit(3);
    glReadBuffer(GL_FRONT);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, w, h, GL_RGB, GL_UNSIGNED_BYTE, pixels);
    FILE *f = fopen(frame_path, "wb");
    if (!f) exit(4);
    fprintf(f, "P6\n%d %d\n255\n", w, h);
    for (int row = h - 1; row >= 0; --row) fwrite(pixels + (size_t)row * w * 3, 1, (size_t)w * 3, f);
    fclose(f);
    free(pixels);
    exit(0);
}

void display(void) {
    GLfloat position[] = {10.0, 5.0, 20.0, 1.0};

    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);      /* change 1 */
    glColor3f(1.0, 1.0, 1.0);
    glLoadIdentity();
    gluLookAt(0.0, 0.0, 8.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0); /* change 2 */
    glLightfv(GL_LIGHT0, GL_POSITION, position);
    glutSolidSphere(1.0, 32, 32);
    glFlush();

    if (frame_path) dump_frame_and_exit();
}

void reshape(int w, int h) {
    glViewport(0, 0, (GLsizei)w, (GLsizei)h);
    glMatrixMode(GL_PROJECTION);
    glLoadIdentity();
    gluPerspective((GLdouble)30, (GLdouble)w / (GLdouble)h, (GLdouble)2, (GLdouble)100);
    glMatrixMode(GL_MODELVIEW);
    glLoadIdentity();
}

void initlights(void) {
    GLfloat ambient[] = {0.1, 0.1, 0.1, 1.0};
    GLfloat diffuse[] = {0.9, 0.9, 0.9, 1.0};
    GLfloat specular[] = {0.5, 0.5, 0.5, 1.0};
    GLfloat mat_diffuse[] = {0.3, 0.9, 0.5, 1.0};
    GLfloat mat_specular[] = {0.1, 0.1, 0.1, 1.0};
    GLfloat mat_shininess[] = {50.0};

    glMaterialfv(GL_FRONT, GL_DIFFUSE, mat_diffuse);
    glMaterialfv(GL_FRONT, GL_SPECULAR, mat_specular);
    glMaterialfv(GL_FRONT, GL_SHININESS, mat_shininess);

    glLightModeli(GL_LIGHT_MODEL_LOCAL_VIEWER, 1);
    glLightModelfv(GL_LIGHT_MODEL_AMBIENT, ambient);

    glLightfv(GL_LIGHT0, GL_DIFFUSE, diffuse);
    glLightfv(GL_LIGHT0, GL_SPECULAR, specular);

    glEnable(GL_LIGHTING);
    glEnable(GL_LIGHT0);
    glEnable(GL_DEPTH_TEST);
}

void init(void) {
    glClearColor(0.0, 0.0, 0.0, 0.0);
    glShadeModel(GL_SMOOTH);
    initlights();
}

void keyboard(unsigned char key, int x, int y) {
    (void)x;
    (void)y;
    switch (key) {
        case 'q':
            exit(0);
            break;
        default:
            break;
    }
}

int main(int argc, char **argv) {
    glutInit(&argc, argv);
    if (argc > 2) {                                          /* change 3 */
        window_width = atoi(argv[1]);
        window_height = atoi(argv[2]);
    }
    if (argc > 3) frame_path = argv[3];                      /* change 4 */
    glutInitDisplayMode(GLUT_SINGLE | GLUT_RGB | GLUT_DEPTH);
    glutInitWindowSize(window_width, window_height);
    glutInitWindowPosition(100, 100);
    glutCreateWindow("Sphere");
    init();

    glutDisplayFunc(display);
    glutReshapeFunc(reshape);
    glutKeyboardFunc(keyboard);

    glutMainLoop();
    return 0;
}
