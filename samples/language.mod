MODULE LanguageTour(SYSMODULE, NOSTEPIN)
  ! Uses the rest of RAPID: records, alias, arrays, traps, error handlers,
  ! TEST/CASE, late binding, CONNECT, GOTO, optional parameters, functions.
  RECORD partinfo
    string name;
    num count;
    bool Stop;
    pos MoveL;
  ENDRECORD
  ALIAS num level;
  LOCAL ALIAS partinfo part;

  CONST num MAX_PARTS:=4;
  CONST num nHex:=0x1F;
  CONST num nHalf:=.5;
  CONST num nScale:=+2.5E-1;
  CONST num nMix:=(nHex + 1) DIV 3 MOD 4 * -nHalf;
  VAR num grid{3,2}:=[[1,2],[3,4],[5,6]];
  VAR num buf{MAX_PARTS,2};
  VAR partinfo parts{2}:=[["bolt",0,FALSE,[0,0,0]],["nut ""M8""",0,TRUE,[1,2,3]]];
  VAR intnum irStop;
  VAR iodev logfile;
  VAR level lvl:=2;
  VAR string procName:="Station";
  PERS bool bRunning:=FALSE;
  VAR num reg1:=0;
  CONST robtarget pRef:=[[500,0,600],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  VAR robtarget pFile:=[[0,0,0],[1,0,0,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  VAR robtarget pSearch;
  VAR jointtarget jNow;

  PROC main()
    VAR num i;
    VAR bool ok:=TRUE;

    CONNECT irStop WITH StopTrap;
    ISignalDI diStop, 1, irStop;
    bRunning := TRUE;
    FOR i FROM 1 TO MAX_PARTS STEP 1 DO
      buf{i, 1} := i * 2;
      buf{i,
          2} := grid{(i MOD 3) + 1, 2} + parts{1}.count;
    ENDFOR
    TEST lvl
    CASE 1, 2:
      %procName + NumToStr(lvl, 0)% \Fast;
    CASE 3:
      Station3;
    DEFAULT:
      TPWrite "unknown level " \Num:=lvl;
    ENDTEST
    IF ok AND NOT bRunning OR reg1 <> 0 XOR FALSE THEN
      reg1 := -1;
    ELSEIF reg1 >= 10 THEN
      reg1 := 0;
    ELSE
      Incr reg1;
    ENDIF
    IF reg1 > 100 GOTO done;
    WHILE reg1 < 3 DO
      reg1 := reg1 + 1;
    ENDWHILE
    ReadTarget;
    MoveL pFile, v200, fine, tool0;
    SearchL \Stop, diProbe, pSearch, Offs(pRef, 0, 0, -50), v20, tool0;
    MoveL pSearch, v50, fine, tool0;
    jNow := CJointT();
    MoveAbsJ jNow, v100, fine, tool0;
    MoveL pRef,
      v500,
      z10,
      tool0
      \WObj:=wobj0;
  done:
    Stop;
  ERROR
    IF ERRNO = ERR_DIVZERO THEN
      TRYNEXT;
    ENDIF
    RAISE;
  ENDPROC

  PROC Station1(\switch Fast | switch Slow, \num Speed)
    IF Present(Fast) THEN
      MoveL Offs(pRef, 0, 0, 100), v1000, z10, tool0 \V?Speed;
    ENDIF
  BACKWARD
    MoveL pRef, v100, fine, tool0;
  UNDO
    bRunning := FALSE;
  ENDPROC

  PROC Station2(\switch Fast) MoveJ pRef, v100, z10, tool0; ENDPROC

  PROC Station3()
    RETURN;
  ENDPROC

  PROC ReadTarget()
    Open "HOME:" \File:="target.bin", logfile \Read;
    ReadAnyBin logfile, pFile;
    Close logfile;
  ERROR (ERR_FILEOPEN, 41)
    RETRY;
  ENDPROC

  FUNC num Average(num values{*}, INOUT num n
      \num Weight)
    VAR num sum:=0;
    FOR k FROM 1 TO Dim(values, 1) DO
      sum := sum + values{k};
    ENDFOR
    n := Dim(values, 1);
    RETURN sum / n;
  ERROR
    IF ERRNO = ERR_DIVZERO RETURN 0;
    EXIT;
  ENDFUNC

  TRAP StopTrap
    bRunning := FALSE;
    StopMove;
  ENDTRAP
ENDMODULE
