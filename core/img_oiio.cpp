// placeholder
extern "C" int img_oiio_placeholder(void); int img_oiio_placeholder(void) { return 0; }
