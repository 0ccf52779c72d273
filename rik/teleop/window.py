"""The viewer teleop's window: a GLFW window of its own (no MuJoCo viewer, so no viewer shortcut collides with a
teleop key) that MuJoCo renders a scene into, with text overlays, three cameras (the front camera, the wrist
camera, a free camera the mouse orbits) and the keyboard polled for held keys. No session logic here:
:mod:`rik.teleop.desktop` runs the loop."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

from rik.errors import RikError

if TYPE_CHECKING:
    from rik.sim.scene import SimScene

SIZE = (800, 600)
"""Window size, pixels (width, height)."""
CAMERAS = ("front", "wrist", "free")
"""Keys 1, 2, 3 pick these cameras."""
FREE_DISTANCE = 1.4
"""The free camera's start distance from the operated handle, m."""


class TeleopWindow:
    """A window showing ``scene`` (shadows and reflections off: they cost ~5x on a software renderer).

    ``on_press(glfw_key, mods)`` is called for every key press (not its repeats); :meth:`held` polls a key."""

    def __init__(self, scene: SimScene, title: str, on_press: Callable[[int, int], None],
                 size: tuple[int, int] = SIZE) -> None:
        import glfw
        import mujoco

        self.scene = scene
        open_display()
        with _glfw_errors("cannot open an OpenGL window"):
            self.window = glfw.create_window(size[0], size[1], title, None, None)
        if not self.window:
            glfw.terminate()
            raise RikError(f"teleoperation cannot open an OpenGL window on display {_display()} (GLFW made none); "
                           "use rik teleop VARIANT --web for the browser station")
        glfw.make_context_current(self.window)
        glfw.swap_interval(0)
        model = scene.model
        self.option = mujoco.MjvOption()
        self.mjscene = mujoco.MjvScene(model, maxgeom=max(2000, 4 * model.ngeom))
        self.mjscene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = 0
        self.mjscene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = 0
        self.context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_100)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_WINDOW, self.context)
        self.cameras = {name: self._camera(name) for name in CAMERAS}
        self.camera = "front"
        self._on_press = on_press
        self._drag: tuple[int, float, float] | None = None
        self._unseen: set[int] = set()
        """Keys pressed since :meth:`held` last asked for them: a tap that starts and ends between two polls."""
        glfw.set_key_callback(self.window, self._key)
        glfw.set_mouse_button_callback(self.window, self._button)
        glfw.set_cursor_pos_callback(self.window, self._cursor)
        glfw.set_scroll_callback(self.window, self._scroll)

    def _camera(self, name: str) -> Any:
        import mujoco

        model, cam = self.scene.model, mujoco.MjvCamera()
        if name == "free":
            mujoco.mjv_defaultFreeCamera(model, cam)
            cam.lookat[:] = self.scene.grasp_point()
            cam.distance, cam.azimuth, cam.elevation = FREE_DISTANCE, -60.0, -20.0  # from the front, right, above
        else:
            cam.type = mujoco.mjtCamera.mjCAMERA_FIXED
            cam.fixedcamid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, name)
        return cam

    # ---- input ------------------------------------------------------------------------------------------------
    def _key(self, window: Any, key: int, scancode: int, action: int, mods: int) -> None:
        import glfw

        if action == glfw.PRESS:
            self._unseen.add(key)
            self._on_press(key, mods)

    def held(self, key: int) -> bool:
        """Whether the GLFW key ``key`` is down now, or was pressed since the last call: on a starved machine both
        edges of a short hold can arrive in one poll of events, and the hold would otherwise be lost."""
        import glfw

        tapped = key in self._unseen
        self._unseen.discard(key)
        return tapped or glfw.get_key(self.window, key) == glfw.PRESS

    def _button(self, window: Any, button: int, action: int, mods: int) -> None:
        import glfw

        if action == glfw.PRESS:
            x, y = glfw.get_cursor_pos(window)
            self._drag = (button, x, y)
        elif self._drag is not None and self._drag[0] == button:
            self._drag = None

    def _cursor(self, window: Any, x: float, y: float) -> None:
        """Dragging orbits the free camera (left button), pans it (right button); it switches to it first."""
        import glfw
        import mujoco

        if self._drag is None:
            return
        button, x0, y0 = self._drag
        self._drag = (button, x, y)
        self.camera = "free"
        action = (mujoco.mjtMouse.mjMOUSE_ROTATE_V if button == glfw.MOUSE_BUTTON_LEFT
                  else mujoco.mjtMouse.mjMOUSE_MOVE_V)
        height = glfw.get_window_size(window)[1] or 1
        mujoco.mjv_moveCamera(self.scene.model, action, (x - x0) / height, (y - y0) / height,
                              self.cameras["free"])

    def _scroll(self, window: Any, dx: float, dy: float) -> None:
        import mujoco

        if self.camera == "free":
            mujoco.mjv_moveCamera(self.scene.model, mujoco.mjtMouse.mjMOUSE_ZOOM, 0.0, -0.05 * dy,
                                  self.cameras["free"])

    # ---- output -----------------------------------------------------------------------------------------------
    def poll(self) -> None:
        """Handle the window's pending events (key presses reach ``on_press`` here)."""
        import glfw

        glfw.poll_events()

    @property
    def closing(self) -> bool:
        """The operator closed the window."""
        import glfw

        return bool(glfw.window_should_close(self.window))

    def render(self, overlays: list[tuple[int, str, str]]) -> None:
        """Draw the scene from the current camera with ``(mjtGridPos, left column, right column)`` texts."""
        import glfw
        import mujoco

        width, height = glfw.get_framebuffer_size(self.window)
        viewport = mujoco.MjrRect(0, 0, width, height)
        mujoco.mjv_updateScene(self.scene.model, self.scene.data, self.option, None, self.cameras[self.camera],
                               mujoco.mjtCatBit.mjCAT_ALL, self.mjscene)
        mujoco.mjr_render(viewport, self.mjscene, self.context)
        for grid, left, right in overlays:
            mujoco.mjr_overlay(mujoco.mjtFont.mjFONT_NORMAL, grid, viewport, left, right, self.context)
        glfw.swap_buffers(self.window)

    def close(self) -> None:
        import glfw

        self.context.free()
        glfw.destroy_window(self.window)
        glfw.terminate()


def open_display() -> None:
    """Initialise GLFW on this process's display, or raise one line saying why it cannot (no X server there...)."""
    import glfw

    with _glfw_errors("cannot open a window"):
        ok = glfw.init()
    if not ok:
        raise RikError(f"teleoperation cannot open a window on display {_display()}: GLFW failed to initialise; "
                       "check the display, or use rik teleop VARIANT --web for the browser station")


@contextmanager
def _glfw_errors(what: str) -> Iterator[None]:
    """GLFW's errors inside the block as one-line :class:`RikError` s (outside it they stay warnings)."""
    import glfw

    glfw.ERROR_REPORTING = "raise"
    try:
        yield
    except glfw.GLFWError as exc:
        why = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise RikError(f"teleoperation {what} on display {_display()}: {why}; check the display, or use rik "
                       "teleop VARIANT --web for the browser station") from None
    finally:
        glfw.ERROR_REPORTING = "warn"


def _display() -> str:
    import os

    return os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY") or "none"
