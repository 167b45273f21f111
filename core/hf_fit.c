/* placeholder */ typedef int glint_placeholder_hf_fit;
