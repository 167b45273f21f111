/* placeholder */ typedef int glint_placeholder_scene;
