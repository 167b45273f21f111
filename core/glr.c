/* placeholder */ typedef int glint_placeholder_glr;
