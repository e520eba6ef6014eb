"""app: the imgui-bundle editor. GUI only: it edits scene state and calls cloudcore."""
