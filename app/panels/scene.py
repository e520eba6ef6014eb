"""The Scene panel: open, save, undo, recover, import and export OpenVDB clouds, and the editor's messages."""

from __future__ import annotations

from pathlib import Path

from imgui_bundle import imgui

from app.editor import Editor, recovery_path


class ScenePanel:
    def __init__(self, editor: Editor):
        self.editor = editor
        self.file_field = str(editor.path or "")
        self.vdb_field = ""

    def draw(self) -> None:
        editor = self.editor
        # the file's name first, with the mark of unsaved edits beside it: at the end of a whole path the
        # mark fell past a panel's edge; the path is the tooltip
        imgui.text(f"{editor.path.name if editor.path else '(unsaved scene)'}{' *' if editor.dirty else ''}")
        if editor.path is not None:
            imgui.set_item_tooltip(str(editor.path))
        _, self.file_field = imgui.input_text("File", self.file_field)
        if imgui.button("Open"):
            editor.open_file(Path(self.file_field))
        imgui.same_line()
        if imgui.button("Save"):
            editor.save()
        imgui.same_line()
        if imgui.button("Save as"):
            editor.save(Path(self.file_field))
        imgui.same_line()
        if imgui.button("Undo"):
            editor.undo()
        imgui.same_line()
        if imgui.button("Redo"):
            editor.redo()
        if editor.path is not None and recovery_path(editor.path).exists():
            if imgui.button("Recover unsaved edits"):
                editor.recover()
            imgui.set_item_tooltip(f"load {recovery_path(editor.path)}, written before the last session ended")
        _, self.vdb_field = imgui.input_text("VDB file", self.vdb_field)
        if imgui.button("Import VDB..."):
            editor.import_vdb(Path(self.vdb_field))
        imgui.set_item_tooltip("add a cloud for each density grid of the OpenVDB file")
        imgui.same_line()
        if imgui.button("Export VDB..."):
            editor.export_vdb(Path(self.vdb_field))
        imgui.set_item_tooltip("write the clouds to the OpenVDB file, one extinction grid a cloud")
        for path in editor.recent[1:]:
            if imgui.small_button(f"recent: {path.name}##{path}"):
                self.file_field = str(path)
                editor.open_file(path)
            imgui.set_item_tooltip(str(path))
        imgui.separator()
        for message in reversed(editor.messages):
            imgui.text_wrapped(message)
