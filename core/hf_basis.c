/* placeholder */ typedef int glint_placeholder_hf_basis;
