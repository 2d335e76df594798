/*
 * H-SLAM for ViSP.
 */
/*!
  \file vpHSlamLog.h
  \brief Process-wide, silent-by-default message reporting for the visp_hslam module.
*/
#ifndef VP_HSLAM_LOG_H
#define VP_HSLAM_LOG_H

#include <visp3/core/vpConfig.h>

#include <functional>
#include <sstream>
#include <string>

/*!
  \class vpHSlamLog
  \ingroup group_hslam
  \brief Where the library's messages go: a verbosity level and a sink chosen by the program.

  What it is for: library code never prints, yet a person running a tutorial wants to know that a calibration was
  missing, a keyframe was dropped or a loop was closed. Library code therefore reports through vpHSlamLog, and
  the PROGRAM decides where messages go by installing a sink. The default sink is none: until a program calls
  setSink(), the library is silent and isEnabled() is false for every level, so building a message costs nothing.
  stderrSink() is a ready-made sink that writes one line per message to standard error.

  Levels, from most to least severe: error, warning, info, debug. A message is delivered when its level is at or
  above the process-wide level (i.e. `level <= getLevel()` in enum order); the default level is info.

  Threading and ownership: the level and the sink are process-wide. One mutex guards the sink and is held only to
  copy a reference to it; the sink itself is called outside the lock, so it may be called from several threads
  at once and must be thread-safe (stderrSink() is: each message is one write of a complete line). A sink that
  is replaced while running stays alive until that call returns. isEnabled() reads two atomics and takes no lock.
  Exceptions thrown by a sink are swallowed: reporting never changes what the library computes.

  \code
  // In a program (tutorial, tool): show warnings and errors on stderr.
  vpHSlamLog::setSink(vpHSlamLog::stderrSink());
  vpHSlamLog::setLevel(vpHSlamLog::warning);

  // In library code: the stream expression is only evaluated when the message would be delivered.
  VP_HSLAM_LOG(vpHSlamLog::info, "loaded " << count << " images from " << folder);
  \endcode
*/
class VISP_EXPORT vpHSlamLog
{
public:
  //! Severity of a message, most severe first.
  enum Level {
    error = 0,   //!< The operation failed (reported before an exception or a lost track).
    warning = 1, //!< Something is degraded but goes on (missing calibration, tracking lost and recovered).
    info = 2,    //!< Milestones a user wants to see (files loaded, initialisation, loop closed).
    debug = 3    //!< Details for developers (per-keyframe statistics, optimiser iterations).
  };

  //! Receiver of messages. Called with the message level and text (no trailing newline).
  typedef std::function<void(Level, const std::string &)> Sink;

  //! Set the process-wide level: messages of this level and more severe ones are delivered.
  static void setLevel(Level level);
  //! The process-wide level (info unless changed).
  static Level getLevel();

  //! Install a sink; an empty function restores the default (silent).
  static void setSink(const Sink &sink);
  //! True when a sink is installed.
  static bool hasSink();

  //! A sink writing "[hslam] <level>: <message>" lines to standard error, for programs.
  static Sink stderrSink();

  //! True when a message of this level would reach a sink: cheap (no lock), use it to skip building messages.
  static bool isEnabled(Level level);

  //! Deliver a message to the sink if isEnabled(level); otherwise do nothing.
  static void log(Level level, const std::string &message);

  //! "error", "warning", "info" or "debug".
  static const char *levelName(Level level);

  /*!
    Parse a level name as a program option would give it ("error", "warning", "info", "debug", case-insensitive,
    or the digits 0 to 3).
    \exception vpHSlamException::invalidArgument for anything else, quoting the text.
  */
  static Level levelFromString(const std::string &name);
};

/*!
  Log a message built with stream syntax, evaluating the stream expression only when the level is enabled.
  \code
  VP_HSLAM_LOG(vpHSlamLog::warning, "no photometric calibration in " << folder << ", estimating brightness");
  \endcode
*/
#define VP_HSLAM_LOG(level, streamExpression)                                                                          \
  do {                                                                                                                 \
    if (vpHSlamLog::isEnabled(level)) {                                                                                \
      std::ostringstream vpHSlamLogStream_;                                                                            \
      vpHSlamLogStream_ << streamExpression;                                                                           \
      vpHSlamLog::log(level, vpHSlamLogStream_.str());                                                                 \
    }                                                                                                                  \
  } while (false)

#endif
